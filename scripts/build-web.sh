#!/usr/bin/env bash
# Builds the site into dist/: the release wasm, its wasm-bindgen glue, web/ and public/, and
# the three.js example of the stance-ik package (dist/examples/three).
# Cargo and wasm-bindgen only redo work when their inputs changed.
set -euo pipefail
cd "$(dirname "$0")/.."
# What ships is compiled by plain rustc, even when called from the tests' clippy builds
# (scripts/clippy-env.sh): clippy-driver turns MIR optimisations off.
unset RUSTC_WORKSPACE_WRAPPER CLIPPY_ARGS
say() { printf '\033[1;34m[build]\033[0m %s\n' "$*"; }

say "compiling stance_web for wasm32 (release)"
cargo build --release -p stance_web --target wasm32-unknown-unknown
wasm=${CARGO_TARGET_DIR:-target}/wasm32-unknown-unknown/release/stance_web.wasm
mkdir -p dist/pkg
if [ ! -f dist/pkg/stance_web_bg.wasm ] || [ "$wasm" -nt dist/pkg/stance_web_bg.wasm ]; then
  say "wasm-bindgen"
  # No wasm-opt here (scripts/build-package.sh runs it on the package): on this module binaryen 132's
  # -Oz, -Os and -O2 cut the raw size by 8-10 % but make it 2-3 % larger gzipped and 5 %
  # larger in brotli, what the page downloads; its dead-code passes alone save 0.5 % for
  # 40 s of build.
  wasm-bindgen --target web --no-typescript --remove-name-section --out-dir dist/pkg "$wasm"
fi
cp -r web/. dist/
cp -r public/. dist/

# The pose detector of File > Open photo (web/photo-worker.js), served by the site itself:
# MediaPipe Pose from its npm package (Apache-2.0; public/vendor/mediapipe-pose/ holds its
# licence and notice), the "full" landmark model only. Loaded when a photo is opened.
mediapipe=node_modules/@mediapipe/pose
mkdir -p dist/vendor/mediapipe-pose
for file in pose.js pose_solution_packed_assets_loader.js pose_solution_packed_assets.data \
  pose_solution_simd_wasm_bin.js pose_solution_simd_wasm_bin.wasm pose_solution_simd_wasm_bin.data \
  pose_solution_wasm_bin.js pose_solution_wasm_bin.wasm pose_web.binarypb \
  pose_landmark_full.tflite; do
  cp "$mediapipe/$file" dist/vendor/mediapipe-pose/
done

# The three.js example (examples/three, served at /examples/three/): the page, the stance-ik
# package and the three.js modules it imports.
bash scripts/build-package.sh
example=dist/examples/three
mkdir -p "$example/stance-ik/pkg" "$example/vendor/three/build" \
  "$example/vendor/three/examples/jsm/loaders" "$example/vendor/three/examples/jsm/utils" \
  "$example/vendor/three/examples/jsm/libs"
cp examples/three/index.html examples/three/main.js "$example/"
cp packages/stance-ik/index.js "$example/stance-ik/"
cp packages/stance-ik/pkg/stance_ik.js packages/stance-ik/pkg/stance_ik_bg.wasm \
  packages/stance-ik/pkg/stance_ik_motion.js packages/stance-ik/pkg/stance_ik_motion_bg.wasm \
  "$example/stance-ik/pkg/"
three=node_modules/three
cp "$three/build/three.module.js" "$three/build/three.core.js" "$example/vendor/three/build/"
cp "$three/examples/jsm/loaders/GLTFLoader.js" "$example/vendor/three/examples/jsm/loaders/"
cp "$three/examples/jsm/utils/BufferGeometryUtils.js" "$example/vendor/three/examples/jsm/utils/"
cp "$three/examples/jsm/libs/meshopt_decoder.module.js" "$example/vendor/three/examples/jsm/libs/"
# Precompressed copies (brotli and gzip) that scripts/serve.mjs sends where accepted.
node scripts/precompress.mjs dist/pkg/stance_web_bg.wasm dist/pkg/stance_web.js \
  "$example/stance-ik/pkg/stance_ik_bg.wasm" "$example/stance-ik/pkg/stance_ik_motion_bg.wasm"
size=$(stat -c %s dist/pkg/stance_web_bg.wasm)
gzip_size=$(stat -c %s dist/pkg/stance_web_bg.wasm.gz)
brotli_size=$(stat -c %s dist/pkg/stance_web_bg.wasm.br)
echo "$gzip_size" > dist/pkg/wasm-gzip-bytes.txt
say "dist/ ready: wasm $((size / 1024)) KiB, $((gzip_size / 1024)) KiB gzipped, $((brotli_size / 1024)) KiB brotli"
