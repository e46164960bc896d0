#!/usr/bin/env bash
# Builds the `stance-ik` npm package (packages/stance-ik/pkg) from crates/stance_js with
# wasm-pack (release, ES module for browsers and Node), then binaryen's wasm-opt -Oz from the
# npm `binaryen` package (a JavaScript/wasm build that installs offline with the other npm
# packages; wasm-pack cannot download binaryen here and Debian's binaryen 108 breaks the
# module): it drops wasm-pack's name section and shrinks the code. Checks that the package's version is the workspace's. wasm-pack finds the pinned
# wasm-bindgen CLI that setup.sh installs. Quick when nothing changed: wasm-pack and wasm-opt
# run only when cargo's wasm is newer than the package's. `npm pack` in packages/stance-ik
# runs this first (its prepack).
set -euo pipefail
cd "$(dirname "$0")/.."
# What ships is compiled by plain rustc (see scripts/clippy-env.sh).
unset RUSTC_WORKSPACE_WRAPPER CLIPPY_ARGS
say() { printf '\033[1;34m[package]\033[0m %s\n' "$*"; }

workspace=$(sed -n '/^\[workspace.package\]/,/^\[/s/^version = "\(.*\)"/\1/p' Cargo.toml)
package=$(node -p 'require("./packages/stance-ik/package.json").version')
if [ "$workspace" != "$package" ]; then
  echo "packages/stance-ik/package.json is version $package, the workspace $workspace" >&2
  exit 1
fi
pkg=packages/stance-ik/pkg
# The same build wasm-pack makes (release, wasm32): when its output is not newer than the
# package's wasm, the package is up to date.
cargo build --quiet --release -p stance_js --lib --target wasm32-unknown-unknown
wasm=${CARGO_TARGET_DIR:-target}/wasm32-unknown-unknown/release/stance_js.wasm
if [ -f "$pkg/stance_ik_bg.wasm" ] && [ -f "$pkg/stance_ik.js" ] && [ ! "$wasm" -nt "$pkg/stance_ik_bg.wasm" ]; then
  say "packages/stance-ik is up to date"
else
  say "wasm-pack build crates/stance_js (release)"
  rm -f "$pkg/stance_ik_bg.wasm"
  # A build that stops half way leaves no wasm behind (else the next run reads it as done).
  trap 'rm -f "$pkg/stance_ik_bg.wasm"' ERR
  wasm-pack --quiet build crates/stance_js --release --target web --no-pack \
    --out-dir ../../packages/stance-ik/pkg --out-name stance_ik
  # The features rustc's wasm32 target emits with the workspace's flags (simd128 from
  # .cargo/config.toml): wasm-opt keeps the module within them.
  node_modules/.bin/wasm-opt -Oz --enable-simd --enable-bulk-memory --enable-bulk-memory-opt \
    --enable-sign-ext --enable-mutable-globals --enable-nontrapping-float-to-int \
    --enable-reference-types --enable-multivalue --enable-call-indirect-overlong \
    "$pkg/stance_ik_bg.wasm" -o "$pkg/stance_ik_bg.wasm"
  trap - ERR
fi
gzip_size=$(gzip -9 -c "$pkg/stance_ik_bg.wasm" | wc -c)
say "packages/stance-ik ready: wasm $((gzip_size / 1024)) KiB gzipped"
