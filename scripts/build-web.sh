#!/usr/bin/env bash
# Builds the site into dist/: the release wasm, its wasm-bindgen glue, web/ and public/.
# Cargo and wasm-bindgen only redo work when their inputs changed.
set -euo pipefail
cd "$(dirname "$0")/.."
say() { printf '\033[1;34m[build]\033[0m %s\n' "$*"; }

say "compiling stance_web for wasm32 (release)"
cargo build --release -p stance_web --target wasm32-unknown-unknown
wasm=target/wasm32-unknown-unknown/release/stance_web.wasm
mkdir -p dist/pkg
if [ ! -f dist/pkg/stance_web_bg.wasm ] || [ "$wasm" -nt dist/pkg/stance_web_bg.wasm ]; then
  say "wasm-bindgen"
  wasm-bindgen --target web --no-typescript --remove-name-section --out-dir dist/pkg "$wasm"
fi
cp -r web/. dist/
cp -r public/. dist/
size=$(stat -c %s dist/pkg/stance_web_bg.wasm)
gzip_size=$(gzip -9 -c dist/pkg/stance_web_bg.wasm | wc -c)
echo "$gzip_size" > dist/pkg/wasm-gzip-bytes.txt
say "dist/ ready: wasm $((size / 1024)) KiB, $((gzip_size / 1024)) KiB gzipped"
