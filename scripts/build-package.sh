#!/usr/bin/env bash
# Builds the `stance-ik` npm package's two WebAssembly modules (packages/stance-ik/pkg): the
# solver from crates/stance_js (`stance_ik*`, what an import loads) and retargeting from
# crates/stance_js_motion (`stance_ik_motion*`, loaded by the first `retarget` call). Each is
# compiled as a cdylib by `cargo rustc --crate-type cdylib` (release, wasm32), given its ES
# module glue by the pinned wasm-bindgen CLI that setup.sh installs (as the page's), then put
# through binaryen's wasm-opt -Oz from the npm `binaryen` package (a JavaScript/wasm build
# that installs offline with the other npm packages; Debian's binaryen 108 breaks the
# module): it drops the name section and shrinks the code. The crates are plain rlibs
# otherwise: a cdylib crate that another depends on is linked again for each set of features
# (its file name carries no hash), so the package was rebuilt on every run. Checks that the
# package's version is the workspace's. Quick when nothing changed: wasm-bindgen and
# wasm-opt run only when cargo's wasm is newer than the package's. `npm pack` in
# packages/stance-ik runs this first (its prepack).
set -Eeuo pipefail
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
# One module: crate $1 compiled (each in a cargo run of its own: built together, cargo would
# unify features and give the solver's bindings to the retargeting module).
compile() {
  cargo rustc --quiet --release -p "$1" --lib --crate-type cdylib --target wasm32-unknown-unknown
}
# Crate $1's wasm given its glue and shrunk as pkg/$2*, when cargo's is newer.
finish() {
  local crate=$1 name=$2
  local wasm=${CARGO_TARGET_DIR:-target}/wasm32-unknown-unknown/release/$crate.wasm
  local out=$pkg/${name}_bg.wasm
  if [ -f "$out" ] && [ -f "$pkg/$name.js" ] && [ ! "$wasm" -nt "$out" ]; then
    say "$name is up to date"
  else
    say "wasm-bindgen and wasm-opt: crates/$crate as $name"
    rm -f "$out"
    # A build that stops half way leaves no wasm behind (else the next run reads it as done).
    trap 'rm -f "$out"' ERR
    wasm-bindgen --target web --out-dir "$pkg" --out-name "$name" "$wasm"
    # The features rustc's wasm32 target emits with the workspace's flags (simd128 from
    # .cargo/config.toml): wasm-opt keeps the module within them.
    node_modules/.bin/wasm-opt -Oz --enable-simd --enable-bulk-memory --enable-bulk-memory-opt \
      --enable-sign-ext --enable-mutable-globals --enable-nontrapping-float-to-int \
      --enable-reference-types --enable-multivalue --enable-call-indirect-overlong \
      "$out" -o "$out"
    trap - ERR
  fi
  local gzip_size
  gzip_size=$(gzip -9 -c "$out" | wc -c)
  say "$name ready: wasm $((gzip_size / 1024)) KiB gzipped"
}
mkdir -p "$pkg"
compile stance_js
compile stance_js_motion
# wasm-opt takes about 10 s a module: the two side by side, one per core.
finish stance_js stance_ik &
solver=$!
finish stance_js_motion stance_ik_motion &
motion=$!
wait "$solver"
wait "$motion"
