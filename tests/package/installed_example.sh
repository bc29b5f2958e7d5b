#!/usr/bin/env bash
# Issue 14: `cmake --install` into a temporary prefix, then examples/cpp_mapper built against
# that installed package (not the build tree) and run on a 40-frame slice of tum_fr1_rpy. Its
# trajectory.txt and mesh.ply must be byte-identical to `semap run --threads 1` on the same
# frames: the example and the CLI are one code path (semap::Mapper).
# Usage: installed_example.sh SOURCE_DIR BUILD_DIR DATA_DIR
set -euo pipefail
src=$1 build=$2 data=${SEMAP_DATA_DIR:-$3}
tum="$data/tum_fr1_rpy"
if [ ! -d "$tum" ]; then
  if [ "${CI:-}" = true ]; then echo "shared data missing: $tum (set SEMAP_DATA_DIR)"; exit 1; fi
  echo "shared data missing: $tum (skipped)"; exit 77
fi
work=$(mktemp -d "${TMPDIR:-/tmp}/semap_package_XXXXXX")
trap 'rm -rf "$work"' EXIT

cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$src/examples/cpp_mapper" -B "$work/example" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/example" >/dev/null

# The slice: links to the images, the first 40 lines of each list.
mkdir "$work/slice"
ln -s "$tum/rgb" "$tum/depth" "$work/slice/"
# awk reads each list to its end: `grep | head` under pipefail fails when head exits before grep
# has written everything (SIGPIPE), which depends on timing.
for list in rgb.txt depth.txt; do awk '!/^#/ && n++ < 40' "$tum/$list" >"$work/slice/$list"; done
cp "$tum/groundtruth.txt" "$work/slice/"

"$work/example/cpp_mapper" "$work/slice" "$work/example_out" >/dev/null
"$build/semap" run "$work/slice" --out "$work/cli_out" --threads 1 --no-eval --segmenter none >/dev/null
for f in trajectory.txt mesh.ply; do
  cmp "$work/example_out/$f" "$work/cli_out/$f" || { echo "the installed example's $f differs from semap run's"; exit 1; }
done
echo "installed package: example == semap run (trajectory.txt, mesh.ply) on 40 frames"
