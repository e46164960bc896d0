#!/usr/bin/env bash
# Optimises a wasm-bindgen output in place with binaryen's wasm-opt from the npm `binaryen`
# package (node_modules/.bin/wasm-opt, a JavaScript/wasm build: installs offline with the
# other npm packages; wasm-pack cannot download binaryen here, and Debian's binaryen 108
# breaks the module). What ships (the page's wasm, the stance-ik package's) goes through it.
#   scripts/wasm-opt.sh FILE.wasm [LEVEL]    LEVEL: a wasm-opt level, default -Oz
# The features are the ones rustc's wasm32 target emits with the workspace's flags
# (.cargo/config.toml adds simd128): wasm-opt keeps the module within them.
set -euo pipefail
cd "$(dirname "$0")/.."
file=$1
level=${2:--Oz}
opt=node_modules/.bin/wasm-opt
if [ ! -x "$opt" ]; then
  echo "$opt is missing: run scripts/setup.sh (npm's binaryen package)" >&2
  exit 1
fi
before=$(stat -c %s "$file")
started=$SECONDS
"$opt" "$level" \
  --enable-simd --enable-bulk-memory --enable-bulk-memory-opt --enable-sign-ext \
  --enable-mutable-globals --enable-nontrapping-float-to-int --enable-reference-types \
  --enable-multivalue --enable-call-indirect-overlong \
  "$file" -o "$file.opt"
mv "$file.opt" "$file"
printf '\033[1;34m[wasm-opt]\033[0m %s: %d -> %d KiB in %d s\n' "$file" $((before / 1024)) \
  $(($(stat -c %s "$file") / 1024)) $((SECONDS - started))
