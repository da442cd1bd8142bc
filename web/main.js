// The demo page: loads the WebAssembly module (wasm-bindgen's `--target web` output in
// pkg/), builds the renderer and draws a frame per animation frame.
//
// Query parameters: `t=0.5` draws that time in every frame instead of the clock;
// `frames=3` stops after that many frames; `strands`, `wind` and `method` set the
// controls; `groom=URL` shows that groom file (.hair, .tfx or USD) instead of the
// creature (as a file opened or dropped on the picture does); `test=1` (with `t` and
// `frames`) marks the page done once the last frame is shown: <body data-done="ok">
// (or "error") and the title "done" (or "error: ...").
import init, { Demo } from './pkg/pelage_web.js';

const params = new URLSearchParams(location.search);
const fixedT = params.has('t') ? Number(params.get('t')) : null;
const maxFrames = params.has('frames') ? Number(params.get('frames')) : Infinity;
const $ = (id) => document.getElementById(id);
const status = $('status');

function fail(error) {
  const message = error instanceof Error ? error.message : String(error);
  status.textContent = message;
  status.className = 'error';
  console.error(message);
  document.title = `error: ${message}`;
  document.body.dataset.done = 'error';
}

function controls() {
  return [Number($('strands').value), Number($('wind').value), $('method').value];
}

async function main() {
  if (!navigator.gpu) {
    throw new Error('this browser has no WebGPU (navigator.gpu is missing)');
  }
  if (params.has('strands')) $('strands').value = params.get('strands');
  if (params.has('wind')) $('wind').value = params.get('wind');
  $('strands-value').textContent = $('strands').value;
  $('wind-value').textContent = Number($('wind').value).toFixed(1);
  await init();
  const wanted = params.get('method') || 'strand_raster';
  const [strands, wind] = controls();
  const demo = await Demo.create($('view'), strands, wind, wanted);
  $('adapter').textContent =
    `${demo.adapter()}\ntimestamp queries: ${demo.has_timestamps() ? 'yes' : 'no'}`;
  const refusals = demo.refusals();
  $('refusals').textContent = refusals ? `refused here:\n${refusals}` : '';
  for (const name of demo.methods().split(',')) {
    const option = document.createElement('option');
    option.value = option.textContent = name;
    option.selected = name === wanted;
    $('method').append(option);
  }
  const apply = () => {
    $('strands-value').textContent = $('strands').value;
    $('wind-value').textContent = Number($('wind').value).toFixed(1);
    try {
      demo.set(...controls());
      status.textContent = '';
      status.className = '';
    } catch (e) {
      status.textContent = e.message;
      status.className = 'error';
    }
  };
  for (const id of ['strands', 'wind', 'method']) $(id).addEventListener('change', apply);
  $('wind').addEventListener('input', apply);

  // A groom replaces the creature: its own strand count, the slider disabled.
  const showGroom = (bytes, name) => {
    const said = demo.load_groom(new Uint8Array(bytes), name);
    $('groom-info').textContent = said;
    $('strands').value = demo.strands();
    $('strands-value').textContent = demo.strands();
    $('strands').disabled = true;
    $('creature').disabled = false;
    status.textContent = '';
    status.className = '';
  };
  // A file the user picks or drops: an error is shown and the page draws on.
  const openFile = async (file) => {
    try {
      showGroom(await file.arrayBuffer(), file.name);
    } catch (e) {
      status.textContent = e.message;
      status.className = 'error';
    }
  };
  $('groom-file').addEventListener('change', () => {
    if ($('groom-file').files.length > 0) openFile($('groom-file').files[0]);
  });
  for (const target of [$('view'), $('groom-drop')]) {
    target.addEventListener('dragover', (event) => event.preventDefault());
    target.addEventListener('drop', (event) => {
      event.preventDefault();
      if (event.dataTransfer.files.length > 0) openFile(event.dataTransfer.files[0]);
    });
  }
  $('creature').addEventListener('click', () => {
    try {
      demo.show_creature(Number($('strands').value));
      $('strands').disabled = false;
      $('creature').disabled = true;
      $('groom-info').textContent = 'the creature, grown';
    } catch (e) {
      status.textContent = e.message;
      status.className = 'error';
    }
  });
  // A groom named in the URL is shown before the first frame; failing to fetch or read
  // it fails the page (the browser test names one).
  if (params.has('groom')) {
    const url = params.get('groom');
    const response = await fetch(url);
    if (!response.ok) throw new Error(`groom ${url}: HTTP ${response.status}`);
    showGroom(await response.arrayBuffer(), new URL(url, location.href).pathname.split('/').pop());
  }

  const start = performance.now();
  let frames = 0;
  const draw = (now) => {
    try {
      // False while the GPU still has two frames: nothing drawn, try again next time.
      if (demo.frame(fixedT ?? (now - start) / 1000)) frames += 1;
    } catch (e) {
      fail(e);
      return;
    }
    if (frames < maxFrames) {
      requestAnimationFrame(draw);
    } else {
      // The last frame has been shown when the next animation frame runs; its GPU times
      // arrive later (up to 30 s is waited for them: SwiftShader takes seconds a frame).
      requestAnimationFrame(() => finish(300));
    }
  };
  const showTimings = () => {
    const timings = demo.timings();
    const table = timings
      .split('\n')
      .filter((line) => line.includes('\t'))
      .map((line) => {
        const [label, ms] = line.split('\t');
        return `${label.padEnd(34)}${ms.padStart(10)}`;
      })
      .join('\n');
    $('timings').textContent = demo.has_timestamps() ? (timings ? table : 'waiting...') : 'n/a';
    return timings !== '' || !demo.has_timestamps();
  };
  const finish = (tries) => {
    try {
      if (!showTimings() && tries > 0) {
        setTimeout(() => finish(tries - 1), 100);
        return;
      }
    } catch (e) {
      fail(e);
      return;
    }
    document.title = 'done';
    document.body.dataset.done = 'ok';
  };
  // The GPU times twice a second, whatever the frame rate (seconds a frame on a CPU).
  const timer = setInterval(() => {
    try {
      showTimings();
    } catch (e) {
      clearInterval(timer);
      fail(e);
    }
  }, 500);
  requestAnimationFrame(draw);
}

// Anything thrown outside main's own handling ends the test at once.
window.addEventListener('error', (event) => fail(event.error ?? event.message));
window.addEventListener('unhandledrejection', (event) => fail(event.reason));
main().catch(fail);
