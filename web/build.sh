#!/usr/bin/env bash
# Builds the browser demo: crates/pelage-web for wasm32-unknown-unknown (release: see
# the README's "In a browser" for the measured build times), then wasm-bindgen's
# JavaScript glue into web/pkg/. Serve web/ afterwards, e.g.
#   python3 -m http.server --bind 127.0.0.1 --directory web 8000
# and open http://127.0.0.1:8000/ in a browser with WebGPU.
set -euo pipefail
cd "$(dirname "$0")/.."
profile="${PELAGE_WEB_PROFILE:-release}"
target="${CARGO_TARGET_DIR:-target}"
if [ "$profile" = release ]; then flag=--release; else flag=; fi
cargo build --locked -p pelage-web --target wasm32-unknown-unknown $flag
out_dir="$profile"
[ "$profile" = dev ] && out_dir=debug
wasm-bindgen --target web --no-typescript --out-dir web/pkg \
    "$target/wasm32-unknown-unknown/$out_dir/pelage_web.wasm"
ls -l web/pkg/pelage_web_bg.wasm
