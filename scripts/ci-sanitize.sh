#!/usr/bin/env bash
# Issue 8 / 21: the tests that exercise parsing, memory and threads (folders core, io,
# segmentation, pipeline, reliability; not heavy) built and run under AddressSanitizer +
# UndefinedBehaviorSanitizer in build-asan/ (clang, -O1, line tables: the tree ci-fuzz.sh builds
# its targets in, scripts/lib/asan-tree.sh), and the threading tests under ThreadSanitizer in
# build-tsan/ (gcc): the segmentation hand-off (both busy policies), a threaded
# pipeline run, a threaded run with real tracking (its loop-closure worker) and YOLO, and the
# tracker's own threading tests, JOBS processes at a time. One build tree per sanitizer; each
# builds only what it runs.
# SEMAP_ASAN=0 / SEMAP_TSAN=0 skip a part. Any sanitizer report fails: reports abort the
# process (halt_on_error), and the ctest log is searched as well, since tests that run the
# semap CLI only see its exit code.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${SEMAP_JOBS:-$(nproc)}
COMMON=(-G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -DNDEBUG"
        "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -DNDEBUG" -DSEMAP_BUILD_BENCH=OFF -DSEMAP_WITH_OPEN3D=OFF)
SUPP="$PWD/scripts/sanitizer"
source scripts/lib/ccache-env.sh
source scripts/lib/asan-tree.sh
source scripts/lib/ctest-costs.sh

fail_on_reports() {  # $1: a log file
  # The count first: under pipefail, `grep | head` in the condition is false when head exits
  # before grep has written every match (SIGPIPE), i.e. exactly when the reports are many.
  local pattern="ERROR: (Address|Leak|Thread)Sanitizer|WARNING: ThreadSanitizer|runtime error:" reports
  reports=$(grep -cE "$pattern" "$1" || true)
  if [ "$reports" -gt 0 ]; then
    grep -nE "$pattern" "$1" | sed -n 1,20p
    echo "semap sanitize: $reports sanitizer reports in $1"; return 1
  fi
}

# Left out under both sanitizers: two one-thread pipeline runs whose code path another test in
# the list already runs (the inline stages: Determinism.MultiThreadMetricsMatchOneThread...):
# byte identity of two runs, and the recorded-pace run (the same run plus sleeping). 67 + 83 s of
# the ASan step (2026-12-02); with pipeline.threads 1 nothing runs concurrently for TSan to check.
SAME_PATH_ONE_THREAD=(PipelineTest.OneThreadRunsAreByteIdentical PipelineTest.RealtimeRunTakesTheRecordedSpanAndGivesTheSameMap)
SAME_PATH_ONE_THREAD_REGEX=$(IFS='|'; echo "^(${SAME_PATH_ONE_THREAD[*]//./\\.})\$")  # for ctest -E
SAME_PATH_ONE_THREAD_FILTER=$(IFS=':'; echo "${SAME_PATH_ONE_THREAD[*]}")            # for --gtest_filter

start=$SECONDS
if [ "${SEMAP_ASAN:-1}" = 1 ]; then
  configure_asan_tree
  ASAN_FOLDERS=(core io segmentation pipeline reliability)
  cmake --build "$ASAN_BUILD" -j "$JOBS" --target semap "${ASAN_FOLDERS[@]/#/tests_}"
  echo "semap sanitize: ASan+UBSan build in $((SECONDS - start)) s"
  # alloc_dealloc_mismatch=0: PCL 1.13 (built as C++14) gives its point clouds a class-specific
  # aligned operator new that a C++17/20 client does not see, so the shared_ptr deleter instantiated
  # in our code frees them with the global sized delete. Every report of the first full run
  # (2026-11-30) was this one PCL-internal pair (SupervoxelClustering::getVoxels); nothing else.
  # intercept_tls_get_addr=0: up to LLVM 16 the runtime's __tls_get_addr interceptor takes a dynamic
  # TLS block that happens to start 16 bytes past a page boundary for one with a pre-2.25 glibc
  # header and reads the two words before it as its bounds; LeakSanitizer's tracer then dies at
  # exit ("Tracer caught signal 11") after the test passed (google/sanitizers#1353). Which test it
  # hits depends on the memory layout: after the UBSan change of cmake/ubsan-ignorelist.txt it hit
  # two tests of one run, and both again in their rerun (2026-12-07).
  export ASAN_OPTIONS=detect_leaks=1:halt_on_error=1:detect_stack_use_after_return=0:alloc_dealloc_mismatch=0:intercept_tls_get_addr=0
  export LSAN_OPTIONS=suppressions=$SUPP/lsan.supp:print_suppressions=0
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  t0=$SECONDS
  labels=$(IFS='|'; echo "^(${ASAN_FOLDERS[*]})$")
  log=$ASAN_BUILD/Testing/Temporary/LastTest.log
  ctest_costs_restore "$ASAN_BUILD" asan
  if ! (cd "$ASAN_BUILD" && ctest -L "$labels" -LE heavy -E "$SAME_PATH_ONE_THREAD_REGEX" --output-on-failure -j "$JOBS" --timeout 1200); then
    # LeakSanitizer's own stop-the-world tracer segfaulted at exit after a test passed (seen in two
    # clean-clone runs, 2026-12-03, after a MapMerge test; the cause above is now switched off):
    # should it still happen, the failed tests run once more; any other failure fails the step.
    grep -q "LeakSanitizer has encountered a fatal error" "$log" || exit 1
    cp "$log" "$log.first"
    echo "semap sanitize: LeakSanitizer's tracer crashed; running the failed tests once more"
    # By name: ctest numbers the tests of a filtered run in the filtered list, so --rerun-failed
    # (by number) ran a different test (2026-12-03: a 520 s merge test for the 76 s one).
    names=$(cut -d: -f2- "$ASAN_BUILD"/Testing/Temporary/LastTestsFailed.log | sed 's/[][().*+?^$|\\]/\\&/g' | paste -sd'|')
    (cd "$ASAN_BUILD" && ctest -R "^(${names})\$" --output-on-failure -j "$JOBS" --timeout 1200)
    fail_on_reports "$log.first"
  fi
  ctest_costs_save "$ASAN_BUILD" asan
  fail_on_reports "$log"
  echo "semap sanitize: ASan+UBSan on ${ASAN_FOLDERS[*]} passed with no report ($((SECONDS - t0)) s)"
fi

# The TSan tests, one "EXECUTABLE GTEST_FILTER" line per process: each test of test_pipeline a
# process of its own, so that they run JOBS at a time (one process is mostly one core's work).
# The longest first (the pipeline runs); the two one-thread runs above are left out here too.
tsan_tests() {
  build-tsan/tests/pipeline/test_pipeline --gtest_list_tests --gtest_filter="PipelineTest.*:-PipelineTest.CliRunAndConfigErrors:$SAME_PATH_ONE_THREAD_FILTER" |
    awk '/^[^ ]/ { suite = $1 } /^  / { print "build-tsan/tests/pipeline/test_pipeline " suite $1 }'
  echo "build-tsan/tests/tracking/test_tracking_threads *"
  echo "build-tsan/tests/pipeline/test_pipeline_models PipelineModels.ThreadedTrackedRunWithYolo"
  echo "build-tsan/tests/pipeline/test_segmentation_schedule *"
}
run_tsan_test() {  # $1: executable, $2: gtest filter; its log in build-tsan/logs/
  local log="build-tsan/logs/$(basename "$1")-${2//[^A-Za-z0-9]/_}.log"
  "$1" --gtest_filter="$2" >"$log" 2>&1 && return 0
  tail -n 80 "$log"; echo "semap sanitize: TSan test $1 --gtest_filter=$2 failed"; return 1
}
export -f run_tsan_test

if [ "${SEMAP_TSAN:-1}" = 1 ]; then
  t0=$SECONDS
  cmake -S . -B build-tsan "${COMMON[@]}" -DSEMAP_SANITIZE=thread >/dev/null
  cmake --build build-tsan -j "$JOBS" --target test_pipeline test_pipeline_models test_segmentation_schedule \
    test_tracking_threads
  echo "semap sanitize: TSan build in $((SECONDS - t0)) s"
  export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$SUPP/tsan.supp"
  rm -rf build-tsan/logs && mkdir -p build-tsan/logs
  t1=$SECONDS
  tests=$(tsan_tests) || { echo "semap sanitize: cannot list the TSan tests"; exit 1; }
  echo "$tests" | xargs -P "$JOBS" -L 1 bash -c 'run_tsan_test "$@"' _ || { echo "semap sanitize: TSan tests failed"; exit 1; }
  cat build-tsan/logs/*.log >build-tsan/tsan.log
  fail_on_reports build-tsan/tsan.log
  echo "semap sanitize: TSan threading tests ($(echo "$tests" | wc -l) processes) passed with no report ($((SECONDS - t1)) s)"
fi
echo "semap sanitize: done in $((SECONDS - start)) s"
