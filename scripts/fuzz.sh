#!/usr/bin/env bash
# Runs every cargo-fuzz target of the repository (crates/*/fuzz) in turn, SECONDS each
# (default 60), from its committed seeds (crates/<crate>/fuzz/seeds/<target>) plus the corpus
# earlier runs grew (crates/<crate>/fuzz/corpus/<target>, not committed), and prints one line
# per target: runs, coverage edges (libFuzzer's `cov:`) and crashes (new files in
# crates/<crate>/fuzz/artifacts/<target>). Exits non-zero when any target crashed.
#   scripts/fuzz.sh [--fresh] [--no-seeds] [SECONDS] [TARGET...]
#     --fresh     start from an empty corpus (a temporary one) instead of the grown one
#     --no-seeds  leave the committed seeds out (with --fresh: an empty start, to compare)
#     TARGET      only these targets (e.g. import link); default: all
# Installs what it needs when missing: the nightly toolchain and cargo-fuzz. Builds into
# $FUZZ_TARGET_DIR (default: ${CARGO_TARGET_DIR:-target}/fuzz). Not part of CI.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

fresh=0
seeds=1
while [ $# -gt 0 ]; do
  case "$1" in
    --fresh) fresh=1; shift ;;
    --no-seeds) seeds=0; shift ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) break ;;
  esac
done
seconds=60
if [ $# -gt 0 ] && [[ "$1" =~ ^[0-9]+$ ]]; then
  seconds=$1
  shift
fi
only=("$@")

say() { printf '\033[1;34m[fuzz]\033[0m %s\n' "$*" >&2; }

if ! rustup run nightly rustc --version >/dev/null 2>&1; then
  say "installing the nightly toolchain (cargo-fuzz needs it)"
  rustup toolchain install nightly --profile minimal
fi
if ! command -v cargo-fuzz >/dev/null; then
  say "installing cargo-fuzz (a few minutes, once)"
  cargo install cargo-fuzz --locked
fi

target_dir=${FUZZ_TARGET_DIR:-${CARGO_TARGET_DIR:-$root/target}/fuzz}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

summary=()
crashed=0
for fuzz_dir in crates/*/fuzz; do
  [ -f "$fuzz_dir/Cargo.toml" ] || continue
  for target in $(cargo +nightly fuzz list --fuzz-dir "$fuzz_dir"); do
    if [ ${#only[@]} -gt 0 ] && [[ ! " ${only[*]} " == *" $target "* ]]; then
      continue
    fi
    if [ "$fresh" = 1 ]; then
      corpus="$work/corpus-$target"
    else
      corpus="$fuzz_dir/corpus/$target"
    fi
    artifacts="$fuzz_dir/artifacts/$target"
    mkdir -p "$corpus" "$artifacts"
    dirs=("$corpus")
    if [ "$seeds" = 1 ] && [ -d "$fuzz_dir/seeds/$target" ]; then
      dirs+=("$fuzz_dir/seeds/$target")
    fi
    ls "$artifacts" | sort >"$work/before"
    log="$work/$target.log"
    say "$target ($fuzz_dir): ${seconds} s from ${dirs[*]}"
    status=0
    # The build's output and libFuzzer's status lines go to the log; a crash's report is
    # printed below.
    cargo +nightly fuzz run --fuzz-dir "$fuzz_dir" --target-dir "$target_dir" "$target" \
      "${dirs[@]}" -- -max_total_time="$seconds" -timeout=30 -print_final_stats=1 \
      >"$log" 2>&1 || status=$?
    runs=$(sed -n 's/^stat::number_of_executed_units: *\([0-9]*\).*/\1/p' "$log" | tail -n 1)
    if [ -z "$runs" ]; then
      runs=$(sed -n 's/^#\([0-9][0-9]*\).*cov: .*/\1/p' "$log" | tail -n 1)
    fi
    cov=$(sed -n 's/^#[0-9].*cov: \([0-9][0-9]*\).*/\1/p' "$log" | tail -n 1)
    ls "$artifacts" | sort >"$work/after"
    crashes=$(comm -13 "$work/before" "$work/after" | wc -l | tr -d ' ')
    if [ "$status" != 0 ] || [ "$crashes" != 0 ]; then
      crashed=1
      [ "$crashes" != 0 ] || crashes="?"
      say "$target failed (exit $status); the end of its log:"
      tail -n 60 "$log" >&2
      comm -13 "$work/before" "$work/after" | sed "s|^|  new artifact: $artifacts/|" >&2
    fi
    line=$(printf '%-10s runs %10s   cov %6s   crashes %s' "$target" "${runs:-?}" "${cov:-?}" "$crashes")
    echo "$line"
    summary+=("$line")
  done
done
if [ ${#summary[@]} -gt 1 ]; then
  echo "--- ${seconds} s per target"
  printf '%s\n' "${summary[@]}"
fi
if [ ${#summary[@]} = 0 ]; then
  echo "no fuzz target matched: ${only[*]}" >&2
  exit 2
fi
exit "$crashed"
