#!/usr/bin/env bash
# Configures and builds semap (Release) into build/. Extra args go to CMake.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib/ccache-env.sh
JOBS=${SEMAP_JOBS:-$(nproc)}
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build build -j "$JOBS"
