#!/bin/sh
# Builds the browser lab's WebAssembly into web/site/ (docs/browser-lab.md).
# Needs the target once: rustup target add wasm32-unknown-unknown
# Serve web/site/ as static files, e.g. python3 -m http.server -d web/site
set -eu
cd "$(dirname "$0")/.."
cargo build -p vlab-web --target wasm32-unknown-unknown --profile web
cp target/wasm32-unknown-unknown/web/vlab_web.wasm web/site/vlab_web.wasm
ls -l web/site/vlab_web.wasm
