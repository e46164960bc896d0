#!/usr/bin/env bash
# Runs every layer of Stance's tests and its quality gates; stops at the first failure.
#   1. gates: rustfmt, purity of the core crates; clippy (-D warnings) runs inside the test
#      builds below (scripts/clippy-env.sh): natively for all targets, for wasm32 in the
#      browser tests' build; stance_js's wasm32-only code is linted on its own
#   2. native `cargo test --workspace` (includes the lavapipe offscreen render)
#   3. the pure crates' tests in headless Chromium (cargo test for wasm32, one invocation)
#   4. the built site in headless Chromium, WebGL2 and WebGPU (Playwright), and the npm
#      package stance-ik from Node (tests/package.test.mjs)
# Expects scripts/setup.sh --test to have run (npm test does both).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR="${CARGO_TERM_COLOR:-always}"
# CI builds from a fresh clone once: incremental compilation only adds work there.
if [ -n "${CI:-}" ]; then export CARGO_INCREMENTAL=0; fi
# shellcheck source=scripts/clippy-env.sh
source scripts/clippy-env.sh
started=$SECONDS
step() { printf '\n\033[1;34m[test %3ds]\033[0m %s\n' "$((SECONDS - started))" "$*"; }

PURE_CRATES=(stance_hanim stance_ik stance_mocap stance_motion)
# Crates added later join the pure list once they exist (stance_document: the share-link codec).
[ -d crates/stance_document ] && PURE_CRATES+=(stance_document)

step "rustfmt"
cargo fmt --all --check

step "purity: ${PURE_CRATES[*]} depend on no graphics, UI, browser or file-format crate"
for crate in "${PURE_CRATES[@]}"; do
  forbidden=$(cargo tree -p "$crate" -e normal --target all --prefix none --format '{lib}' \
    | sed 's/ (\*)$//' | grep -Ex 'wgpu|egui|eframe|web_sys|wasm_bindgen|gltf|egui_wgpu|js_sys' | sort -u || true)
  if [ -n "$forbidden" ]; then
    echo "$crate depends on: $forbidden" >&2
    exit 1
  fi
done

# The editor's model is not a pure crate (it reads files through stance_asset and builds the
# renderer's plain data, stance_render without its `gpu` feature) and its tests run natively
# only; but it holds no UI, GPU or browser code: the views are stance_editor's (web-time's
# wasm-bindgen, the browser's clock, is allowed).
step "purity: stance_model depends on no UI, GPU or browser crate"
forbidden=$(cargo tree -p stance_model -e normal --target all --prefix none --format '{lib}' \
  | sed 's/ (\*)$//' | grep -Ex 'wgpu|egui|eframe|web_sys|winit|egui_wgpu|egui_kittest' | sort -u || true)
if [ -n "$forbidden" ]; then
  echo "stance_model depends on: $forbidden" >&2
  exit 1
fi

step "fuzz targets: every file in crates/*/fuzz/fuzz_targets is a declared target (scripts/fuzz.sh runs them all)"
for fuzz_dir in crates/*/fuzz; do
  for file in "$fuzz_dir"/fuzz_targets/*.rs; do
    if ! grep -qx "path = \"fuzz_targets/$(basename "$file")\"" "$fuzz_dir/Cargo.toml"; then
      echo "$file is not declared as a [[bin]] in $fuzz_dir/Cargo.toml: cargo fuzz never runs it" >&2
      exit 1
    fi
  done
done

step "native build (with clippy) and tests"
# Every target is built (benches too, as `cargo clippy --all-targets` checked them); no doc
# tests: the crates have none, and each would cost a rustdoc run.
cargo test --workspace --quiet --all-targets --no-run
cargo test --workspace --quiet --lib --bins --tests -- --skip scenario_timings --skip frame_cost
# The S2..S5 timings, printed (the same test prints them in the browser below), and the
# editor's CPU per frame with the shared avatar and Table 1 while pulling.
# Through --workspace, as above: `-p CRATE` would unify other features and build the crate's
# dependencies again (about three minutes on a fresh clone).
cargo test --workspace --quiet --test all -- --nocapture scenario_timings frame_cost

# The pure crates' wasm-bindgen tests in headless Chromium, in one cargo invocation (their
# dependencies built once for all, with the features unified): .cargo/config.toml's runner,
# wasm-bindgen-test-runner, runs each test binary through Debian's chromedriver (what
# `wasm-pack test --headless --chrome` does, one crate at a time). `stance_asset` (the
# importer) is tested natively; in the browser it runs in the release wasm of the page's
# end-to-end avatar tests (picked and broken files), which saves CI about a minute of wasm32
# debug builds.
step "${PURE_CRATES[*]} in headless Chromium (wasm32 tests)"
packages=()
for crate in "${PURE_CRATES[@]}"; do packages+=(-p "$crate"); done
# --nocapture: stance_ik's console output carries its S2..S5 timings. Not --quiet: cargo would
# pass it on to wasm-bindgen-test-runner, which refuses it.
CHROMEDRIVER="$(command -v chromedriver)" cargo test --target wasm32-unknown-unknown \
  "${packages[@]}" --lib --tests -- --nocapture

step "clippy (wasm32): stance_js and stance_js_motion, the npm package's bindings"
env -u RUSTC_WORKSPACE_WRAPPER -u CLIPPY_ARGS \
  cargo clippy --quiet --target wasm32-unknown-unknown -p stance_js -p stance_js_motion --lib \
  -- -D warnings

step "site build (and the stance-ik package with its three.js example)"
# What ships is compiled by plain rustc (see scripts/clippy-env.sh).
env -u RUSTC_WORKSPACE_WRAPPER -u CLIPPY_ARGS bash scripts/build-web.sh

step "end to end in headless Chromium (WebGL2 and WebGPU)"
# The CLI the native tests built (with the workspace's features): tests/browser.mjs would
# otherwise build it alone with `-p stance_cli`, another feature set, from its dependencies up.
export STANCE_BIN="${CARGO_TARGET_DIR:-target}/debug/stance"
[ -x "$STANCE_BIN" ] || { echo "$STANCE_BIN is missing after the native tests" >&2; exit 1; }
# Two files at a time (each file starts its own server on a free port and its own browser
# profile): the machine's two cores are busy either way.
node --test --test-concurrency=2 tests/

step "all green in $((SECONDS - started)) s; wasm $(($(cat dist/pkg/wasm-gzip-bytes.txt) / 1024)) KiB gzipped"
