#!/usr/bin/env bash
# Installs what is missing (Debian 12 packages), configures and builds scatterlab in Release.
# Usage: scripts/setup.sh [BUILD_DIR]   (default: build). Safe to run again: only does what is needed.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-build}

PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libglm-dev libeigen3-dev libtbb-dev nlohmann-json3-dev libcli11-dev
  libopenexr-dev libpng-dev zlib1g-dev libopenvdb-dev libboost-iostreams-dev
  libembree-dev libtinyobjloader-dev libxsimd-dev
  libegl-dev libepoxy-dev libegl-mesa0 libgl1-mesa-dri
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-matplotlib python3-distributed python3-dev python3-numpy pybind11-dev
)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "scatterlab setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

JOBS=${SCATTERLAB_JOBS:-2}
# The Python that the python3-* packages above serve is Debian's /usr/bin/python3; another
# python3 first on PATH (pyenv, conda, a venv) has none of them.
PYTHON_ARGS=()
[ -x /usr/bin/python3 ] && PYTHON_ARGS=(-DPython3_EXECUTABLE=/usr/bin/python3)
# ccache where installed (as scripts/test-sanitize.sh): a rebuild after a branch switch or in a
# second checkout takes the unchanged objects from the cache.
LAUNCHER=()
command -v ccache >/dev/null && LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# The test files themselves at -O1 (the library, the tool and the module keep Release's -O3):
# they compile in two thirds of the time (tests/sampling/test_dynamic_sampling.cpp 19 s
# against 28 s) and the code they test is the same.
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DSCATTERLAB_TEST_CXX_FLAGS=-O1 \
  "${PYTHON_ARGS[@]}" "${LAUNCHER[@]}" >/dev/null
cmake --build "$BUILD_DIR" -j "$JOBS"
