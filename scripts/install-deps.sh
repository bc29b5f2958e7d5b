#!/usr/bin/env bash
# Installs the Debian 12 packages semap needs, only those that are missing.
# Idempotent and quiet when everything is already there.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config ccache
  libeigen3-dev libopencv-dev libpcl-dev libceres-dev libtbb-dev
  nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev libyaml-cpp-dev
  libgtest-dev libgmock-dev libbenchmark-dev libnanoflann-dev
  libopen3d-dev libcpp-httplib-dev libdeflate-dev libsqlite3-dev liblz4-dev libzstd-dev
  librosbag-storage-dev libsensor-msgs-dev libroslz4-dev libbz2-dev libopenni2-dev libopencv-contrib-dev
  pybind11-dev python3-dev python3-numpy python3-yaml python3-pytest python3-opencv python3-open3d python3-dask python3-distributed
  python3-pil  # issue 39: tests/python/test_navigation.py reads map.pgm as map_server does
)
# Extra packages can be requested by callers, e.g. the CI adds clang for fuzzing.
PACKAGES+=("$@")

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  bash "$(dirname "$0")/install-viewer-deps.sh"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "semap: installing ${#missing[@]} missing Debian packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "semap: dependencies installed"
bash "$(dirname "$0")/install-viewer-deps.sh"
