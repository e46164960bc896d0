#!/usr/bin/env bash
# Runs `stance bench --json` natively and as WebAssembly, and prints the wasm/native ratio per
# scenario. The wasm build is the same CLI compiled for wasm32-wasip1 and run by Node's
# built-in WASI (V8, the engine of Chromium); wall-clock time comes from WASI clock_time_get.
#
# Then the same for the sensor decoders (`stance_mocap`'s decode_throughput example): MB/s
# natively and as wasm.
#
# Usage: crates/stance_cli/bench-wasm.sh [extra `stance bench` flags, e.g. --millis 500]
# Needs: rustup target wasm32-wasip1 (added below if missing), node >= 20.
set -euo pipefail
cd "$(dirname "$0")/../.."
target_dir=${CARGO_TARGET_DIR:-target}
rustup target list --installed | grep -q '^wasm32-wasip1$' || rustup target add wasm32-wasip1
cargo build --release -p stance_cli
# simd128: f64x2 for the dot products / axpys of the kernel (all current browsers and Node have
# wasm SIMD); the web build should enable it too.
CARGO_TARGET_WASM32_WASIP1_RUSTFLAGS="${CARGO_TARGET_WASM32_WASIP1_RUSTFLAGS:--C target-feature=+simd128}" \
  cargo build --release -p stance_cli --target wasm32-wasip1
CARGO_TARGET_WASM32_WASIP1_RUSTFLAGS="${CARGO_TARGET_WASM32_WASIP1_RUSTFLAGS:--C target-feature=+simd128}" \
  cargo build --release -p stance_mocap --example decode_throughput --target wasm32-wasip1
cargo build --release -p stance_mocap --example decode_throughput
runner=$(mktemp --suffix=.mjs)
trap 'rm -f "$runner"' EXIT
cat > "$runner" <<'JS'
import { readFile } from 'node:fs/promises';
import { WASI } from 'node:wasi';
const [wasmPath, ...args] = process.argv.slice(2);
const wasi = new WASI({ version: 'preview1', args: ['stance', ...args], env: {}, preopens: { '/': '/' } });
const module = await WebAssembly.compile(await readFile(wasmPath));
const instance = await WebAssembly.instantiate(module, wasi.getImportObject());
process.exitCode = wasi.start(instance);
JS
echo "native..." >&2
native=$("$target_dir/release/stance" bench --json "$@")
echo "wasm (node $(node --version), WASI)..." >&2
wasm=$(node --no-warnings "$runner" "$target_dir/wasm32-wasip1/release/stance.wasm" bench --json "$@")
NATIVE="$native" WASM="$wasm" node -e '
const n = JSON.parse(process.env.NATIVE), w = JSON.parse(process.env.WASM);
const rows = [["", "native us/iter", "wasm us/iter", "ratio", "native us/solve", "wasm us/solve", "ratio"]];
for (const k of Object.keys(n)) {
  const a = n[k], b = w[k];
  rows.push([k, a.us_per_iteration.toFixed(2), b.us_per_iteration.toFixed(2), (b.us_per_iteration / a.us_per_iteration).toFixed(2),
             a.us_per_solve.toFixed(1), b.us_per_solve.toFixed(1), (b.us_per_solve / a.us_per_solve).toFixed(2)]);
}
for (const r of rows) console.log(r.map((c, i) => String(c).padStart(i ? 15 : 3)).join(" "));
console.log(JSON.stringify({ native: n, wasm: w }));
'
echo "decoders, native..." >&2
decode_native=$("$target_dir/release/examples/decode_throughput")
echo "decoders, wasm..." >&2
decode_wasm=$(node --no-warnings "$runner" "$target_dir/wasm32-wasip1/release/examples/decode_throughput.wasm")
NATIVE="$decode_native" WASM="$decode_wasm" node -e '
const parse = (text) => Object.fromEntries(text.trim().split("\n").map((line) => {
  const [name, rate] = line.trim().split(/\s+/);
  return [name, Number(rate)];
}));
const n = parse(process.env.NATIVE), w = parse(process.env.WASM);
console.log("decoder        native MB/s   wasm MB/s   wasm/native");
for (const k of Object.keys(n)) {
  console.log(k.padEnd(12), n[k].toFixed(1).padStart(12), (w[k] ?? NaN).toFixed(1).padStart(11), ((w[k] ?? NaN) / n[k]).toFixed(2).padStart(13));
}
'
