"""The browser test's driver (run by .ci/browser-test): serves web/ from 127.0.0.1 on a
free port, loads the demo page in headless Chromium (WebGPU on SwiftShader) through
Selenium with a fixed frame (`?t=...&frames=3&test=1`), waits until the page says it is
done, fails on any console error, and saves a screenshot of the canvas and of the page.

usage: browser_test.py WEB_DIR OUT_DIR QUERY
"""

import functools
import http.server
import sys
import threading
import time

from selenium import webdriver
from selenium.common.exceptions import TimeoutException
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

# The flags that give headless Chromium WebGPU (compute and canvas) without a GPU.
CHROMIUM_FLAGS = [
    "--headless=new",
    "--no-sandbox",
    "--disable-gpu-sandbox",
    "--enable-unsafe-webgpu",
    "--ignore-gpu-blocklist",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--enable-features=Vulkan",
    "--use-vulkan=swiftshader",
    "--use-webgpu-adapter=swiftshader",
    "--window-size=1000,700",
    "--force-device-scale-factor=1",
]
# How long the page may take to draw its frames (SwiftShader is a CPU rasterizer).
PAGE_TIMEOUT_S = 240


class QuietHandler(http.server.SimpleHTTPRequestHandler):
    """Serves files without a log line per request."""

    extensions_map = {
        **http.server.SimpleHTTPRequestHandler.extensions_map,
        ".wasm": "application/wasm",
        ".js": "text/javascript",
    }

    def log_message(self, format, *args):  # noqa: A002 (the base class's name)
        pass


def main(web_dir, out_dir, query):
    handler = functools.partial(QuietHandler, directory=web_dir)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    port = server.server_address[1]
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for flag in CHROMIUM_FLAGS:
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(
        options=options, service=Service(executable_path="/usr/bin/chromedriver")
    )
    failures = []
    try:
        url = f"http://127.0.0.1:{port}/index.html?{query}"
        started = time.monotonic()
        driver.get(url)
        try:
            WebDriverWait(driver, PAGE_TIMEOUT_S, poll_frequency=0.25).until(
                lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-done")
            )
        except TimeoutException:
            failures.append(f"the page did not finish within {PAGE_TIMEOUT_S} s")
        done = driver.find_element(By.TAG_NAME, "body").get_attribute("data-done")
        print(f"page: {url} -> {done!r} after {time.monotonic() - started:.1f} s")
        print(f"title: {driver.title}")
        for id_ in ("adapter", "refusals", "timings", "status"):
            text = driver.find_element(By.ID, id_).text
            if text:
                print(f"{id_}:\n  " + text.replace("\n", "\n  "))
        if done != "ok":
            failures.append(f"the page says {done!r}: {driver.title}")
        driver.save_screenshot(f"{out_dir}/page.png")
        driver.find_element(By.ID, "view").screenshot(f"{out_dir}/canvas.png")
        for entry in driver.get_log("browser"):
            print(f"console {entry['level']}: {entry['message']}")
            if entry["level"] == "SEVERE":
                failures.append(f"console error: {entry['message']}")
    finally:
        driver.quit()
        server.shutdown()
        server.server_close()
    for failure in failures:
        print(f"FAILED: {failure}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
