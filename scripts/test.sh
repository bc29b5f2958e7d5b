#!/usr/bin/env bash
# Installs what is missing, builds, and runs the fast test suite (heavy tests: ctest -L heavy).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
cd build
ctest -LE heavy --output-on-failure -j "${SEMAP_JOBS:-$(nproc)}" --timeout 900
