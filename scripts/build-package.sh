#!/usr/bin/env bash
# Builds the `stance-ik` npm package (packages/stance-ik/pkg) from crates/stance_js with
# wasm-pack (release, ES module for browsers and Node); checks that the package's version is
# the workspace's. wasm-pack finds the pinned wasm-bindgen CLI that setup.sh installs.
set -euo pipefail
cd "$(dirname "$0")/.."
say() { printf '\033[1;34m[package]\033[0m %s\n' "$*"; }

workspace=$(sed -n '/^\[workspace.package\]/,/^\[/s/^version = "\(.*\)"/\1/p' Cargo.toml)
package=$(node -p 'require("./packages/stance-ik/package.json").version')
if [ "$workspace" != "$package" ]; then
  echo "packages/stance-ik/package.json is version $package, the workspace $workspace" >&2
  exit 1
fi
say "wasm-pack build crates/stance_js (release)"
wasm-pack --quiet build crates/stance_js --release --target web --no-pack \
  --out-dir ../../packages/stance-ik/pkg --out-name stance_ik
gzip_size=$(gzip -9 -c packages/stance-ik/pkg/stance_ik_bg.wasm | wc -c)
say "packages/stance-ik ready: wasm $((gzip_size / 1024)) KiB gzipped"
