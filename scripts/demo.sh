#!/usr/bin/env bash
# The main job: installs what is missing, builds, and runs `semap demo` on the built-in
# synthetic scene.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
./build/semap demo --out "${1:-demo_out}"
