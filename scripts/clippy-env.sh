# Sourced by scripts/test.sh for its test builds: every workspace crate is compiled by
# clippy-driver, so that one build both lints (clippy, -D warnings) and compiles it.
# Dependencies are compiled by plain rustc. Not for what ships: clippy-driver turns MIR
# optimisations off, so the site and the npm package are built by plain rustc (without this).
driver=$(command -v clippy-driver || rustup which clippy-driver 2>/dev/null || true)
if [ -z "$driver" ]; then
  echo "clippy-driver is missing: rustup component add clippy" >&2
  exit 1
fi
export RUSTC_WORKSPACE_WRAPPER="$driver"
export CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__"
