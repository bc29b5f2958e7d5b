#!/usr/bin/env bash
# The quick check of a change (issue 41): builds what the touched folders' tests need in build/
# (Release, incremental, through ccache) and runs the fast tests of those folders only.
#   bash scripts/check.sh            the uncommitted changes, or the last commit when there are none
#   bash scripts/check.sh REV        the changes since REV (e.g. origin/main, HEAD~3)
#   bash scripts/check.sh --all      every folder (the whole fast suite)
# A folder is a test label (tests/CMakeLists.txt): src/X, include/semap/X and tests/X map to X;
# apps/ and viewer/ to apps; python/ to python. A change to the build itself (CMake files,
# scripts/, fuzz/, bench/) checks every folder. The libraries downstream of a change (core is
# under everything) are covered by scripts/test.sh, which CI runs.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib/ccache-env.sh
JOBS=${SEMAP_JOBS:-$(nproc)}
ALL_FOLDERS=(core io synth eval tsdf tracking segmentation objects navigation pipeline apps reliability python)

changed_files() {  # $1: a revision, or empty
  if [ -n "${1:-}" ]; then git diff --name-only "$1" --; git ls-files --others --exclude-standard; return; fi
  local local_changes
  local_changes=$( (git diff --name-only HEAD --; git ls-files --others --exclude-standard) | sort -u)
  if [ -n "$local_changes" ]; then echo "$local_changes"; else git diff --name-only HEAD~1 HEAD --; fi
}

folder_of() {  # a changed path -> a test label, "all", or nothing
  case "$1" in
    src/*|tests/*) local f=${1#*/}; f=${f%%/*}; [ -d "tests/$f" ] && echo "$f" || echo all ;;
    include/semap/*/*) local f=${1#include/semap/}; echo "${f%%/*}" ;;
    include/*) echo all ;;
    apps/*|viewer/*) echo apps ;;
    python/*) echo python ;;
    CMakeLists.txt|*/CMakeLists.txt|cmake/*|scripts/*|fuzz/*|bench/*) echo all ;;
  esac
}

if [ "${1:-}" = --all ]; then
  folders=("${ALL_FOLDERS[@]}")
else
  mapfile -t folders < <(changed_files "${1:-}" | while read -r f; do folder_of "$f"; done | sort -u)
  if printf '%s\n' "${folders[@]}" | grep -qx all; then folders=("${ALL_FOLDERS[@]}"); fi
fi
if [ ${#folders[@]} -eq 0 ] || [ -z "${folders[0]}" ]; then
  echo "semap check: no source change to check"; exit 0
fi
echo "semap check: folders ${folders[*]}"

start=$SECONDS
ccache_zero
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
targets=(semap)
for f in "${folders[@]}"; do
  case "$f" in
    python) targets+=(semap_python semap_python_files) ;;
    *) grep -q "^tests_$f:" <(ninja -C build -t targets all 2>/dev/null) && targets+=("tests_$f") ;;
  esac
done
cmake --build build -j "$JOBS" --target "${targets[@]}"
echo "semap check: build in $((SECONDS - start)) s"
ccache_report "check build"

t0=$SECONDS
labels=$(IFS='|'; echo "^(${folders[*]})$")
(cd build && ctest -L "$labels" -LE heavy --output-on-failure -j "$JOBS" --timeout 900)
echo "semap check: tests of ${folders[*]} in $((SECONDS - t0)) s (total $((SECONDS - start)) s)"
