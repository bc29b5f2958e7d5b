#!/usr/bin/env bash
# Issue 8: builds the libFuzzer targets of fuzz/ (clang, ASan + UBSan) into build-asan/ (the tree
# the sanitizer tests use too, scripts/lib/asan-tree.sh), replays
# the committed regression inputs (fuzz/regressions/TARGET/*), then runs every target for
# SEMAP_FUZZ_SECONDS (default 30) from seeds written by the project's own writers. Fails on any
# crash, sanitizer report, leak, timeout (> 10 s per input) or out-of-memory (> 2 GiB); the
# offending input is kept as build-asan/artifacts/TARGET-crash-*. Prints executions per target.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${SEMAP_JOBS:-$(nproc)}
SECS=${SEMAP_FUZZ_SECONDS:-30}
source scripts/lib/ccache-env.sh
source scripts/lib/asan-tree.sh
BUILD=$ASAN_BUILD

start=$SECONDS
configure_asan_tree
cmake --build "$BUILD" -j "$JOBS" --target fuzz_all
echo "semap fuzz: built in $((SECONDS - start)) s"

export ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1:intercept_tls_get_addr=0  # ci-sanitize.sh says why
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
mkdir -p "$BUILD/artifacts" "$BUILD/logs"

fuzz_one() {
  local exe=$1 secs=$2 build=$3 name
  name=$(basename "$exe")
  local corpus="$build/corpus/$name" log="$build/logs/$name.log"
  rm -rf "$corpus" && mkdir -p "$corpus"
  # Regression inputs first: each is run once.
  if compgen -G "fuzz/regressions/$name/*" >/dev/null; then
    if ! "$exe" -runs=1 fuzz/regressions/"$name"/* >"$build/logs/$name.regressions.log" 2>&1; then
      echo "semap fuzz: $name FAILED on a regression input"; tail -n 40 "$build/logs/$name.regressions.log"; return 1
    fi
  fi
  if ! SEMAP_FUZZ_SEED_DIR="$corpus" "$exe" "$corpus" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 \
      -max_len=65536 -print_final_stats=1 -artifact_prefix="$build/artifacts/$name-" >"$log" 2>&1; then
    echo "semap fuzz: $name FAILED (input kept under $build/artifacts/)"; tail -n 60 "$log"; return 1
  fi
  local execs
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -n 1)
  echo "semap fuzz: $name ok: ${execs:-?} executions in ${secs} s, corpus $(ls "$corpus" | wc -l) inputs"
}
export -f fuzz_one

ls "$BUILD"/fuzz/fuzz_* | xargs -P "$JOBS" -I{} bash -c 'fuzz_one "$@"' _ {} "$SECS" "$BUILD"
echo "semap fuzz: all targets passed ($((SECONDS - start)) s)"
