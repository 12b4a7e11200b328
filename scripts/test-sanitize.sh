#!/usr/bin/env bash
# The test suite under AddressSanitizer + UndefinedBehaviorSanitizer (issue 17): a separate
# build tree (build-asan/, RelWithDebInfo at -O1 -g1), every C++ test including the GPU tests on
# llvmpipe. Not here: the Python module and the installed-package consumer test (a Python
# interpreter that is not ASan-built would need libasan in LD_PRELOAD and reports CPython's
# own leaks; the same code runs in the C++ tests) and the benchmarks.
# Usage: scripts/test-sanitize.sh [BUILD_DIR]   (SCATTERLAB_JOBS: parallel jobs, default 2)
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
BUILD=${1:-build-asan}
JOBS=${SCATTERLAB_JOBS:-2}
# Line tables only (-g1): the sanitizers' stack traces need file and line, not variables, and
# full -g made this tree the slowest part of CI (media/vdb.cpp 309 s at -O1 -g, 208 s at -O1
# -g1; docs/reliability.md). The test executables share one precompiled header
# (tests/CMakeLists.txt). Clang 14, not the Release tree's GCC 12: a cold build of this tree took
# ~18 minutes in CI against GCC's 32 (2 cores; docs/reliability.md, "CI's time"), and the suite runs
# under both compilers' rounding (the Release tree's tests are GCC's).
if ! command -v clang++ >/dev/null; then
  echo "scatterlab test-sanitize: installing clang"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends clang
fi
# A tree configured with another compiler is started afresh (CMake cannot switch in place).
if [ -f "$BUILD/CMakeCache.txt" ] &&
  ! grep -q '^CMAKE_CXX_COMPILER:FILEPATH=.*clang++' "$BUILD/CMakeCache.txt"; then
  rm -rf "$BUILD"
fi
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DSCATTERLAB_SANITIZE=ON \
  -DSCATTERLAB_BUILD_BENCH=OFF -DSCATTERLAB_PYTHON=OFF -DSCATTERLAB_INSTALL=OFF \
  -DPython3_EXECUTABLE=/usr/bin/python3 "${launcher[@]}" >/dev/null
cmake --build "$BUILD" -j "$JOBS"
cd "$BUILD"
# Any report fails the test that caused it: UBSan aborts instead of printing and going on.
# Third-party headers' reports are suppressed one by one in scripts/ubsan.supp (each says why).
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1:suppressions=$ROOT/scripts/ubsan.supp}
# Mesa's shader cache on (validation turns it off so that every compile's warnings are seen,
# gpu/context.cpp): the Release run of scripts/test.sh has checked the same texts; here the
# cache saves ~100 s of compiles.
export MESA_SHADER_CACHE_DISABLE=${MESA_SHADER_CACHE_DISABLE:-false}
# Leaks inside Mesa's llvmpipe driver are not ours (scripts/lsan.supp says which).
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$ROOT/scripts/lsan.supp:print_suppressions=0}
# Run by hand, not by ctest: under ctest (every time, also alone with -R) LeakSanitizer's own
# tracer dies at this test's exit ("Tracer caught signal 11 ... LeakSanitizer has encountered a
# fatal error") after the test passed; run directly, with the same options, working directory
# and piped output, its leak check completes and reports nothing (measured 2026-11-23, 12 runs).
# It still runs under ASan + UBSan + LSan here, only outside ctest.
direct='GpuResident.SogDensitySplattedOnTheGpuEqualsTheCpuSplat'
# The same tracer crash has hit other GPU tests once in a while (2026-11-27:
# GpuCompetitorObjects.MatchesCpu/6 after it passed): a test that fails only that way is run
# again directly by scripts/asan_rerun.py; any other failure fails the run.
set +e
ctest --output-on-failure -j "$JOBS" --timeout 1800 -E "^${direct}\$" 2>&1 | tee ctest-asan.log
rc=${PIPESTATUS[0]}
set -e
if [ "$rc" -ne 0 ]; then
  python3 "$ROOT/scripts/asan_rerun.py" ctest-asan.log
fi
if [ -x bin/test_gpu ]; then
  (cd tests && ../bin/test_gpu --gtest_filter="$direct")
fi
