#!/usr/bin/env bash
# Installs what is missing, builds, and runs the fast test suite (heavy tests: ctest -L heavy),
# then the reliability steps of issue 8: every libFuzzer target for a bounded time
# (scripts/ci-fuzz.sh, clang) and the fast suite under ASan+UBSan plus the pipeline threading
# tests under TSan (scripts/ci-sanitize.sh). SEMAP_QUICK=1 runs the fast suite only.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh clang libclang-rt-14-dev
start=$SECONDS
bash scripts/build.sh
echo "semap test: build in $((SECONDS - start)) s"
t0=$SECONDS
(cd build && ctest -LE heavy --output-on-failure -j "${SEMAP_JOBS:-$(nproc)}" --timeout 900)
echo "semap test: fast suite in $((SECONDS - t0)) s"
if [ "${SEMAP_QUICK:-0}" != 1 ]; then
  t0=$SECONDS
  bash scripts/ci-fuzz.sh
  echo "semap test: fuzzing in $((SECONDS - t0)) s"
  t0=$SECONDS
  bash scripts/ci-sanitize.sh
  echo "semap test: sanitizers in $((SECONDS - t0)) s"
fi
echo "semap test: total $((SECONDS - start)) s"
