#!/usr/bin/env bash
# Sets everything up (scripts/setup.sh), then runs the whole test suite with ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh build
cd build
ctest --output-on-failure -j "${SCATTERLAB_JOBS:-2}" --timeout 900
