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
# (tests/CMakeLists.txt). GCC, as the Release tree: clang 14 builds the tree in half the time
# but the suite is not yet clean under it (docs/reliability.md, "Sanitizers in CI").
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# -Wno-maybe-uninitialized (this tree only): at -O1 with ASan, GCC 12 reports a false
# -Wmaybe-uninitialized inside <regex> (the std::function of std::__detail::_NFA's states, from
# tests/methods/test_key_docs.cpp: 10 warnings); the Release tree keeps the warning.
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCMAKE_CXX_FLAGS="-Wno-maybe-uninitialized" \
  -DSCATTERLAB_SANITIZE=ON \
  -DSCATTERLAB_BUILD_BENCH=OFF -DSCATTERLAB_PYTHON=OFF -DSCATTERLAB_INSTALL=OFF \
  -DPython3_EXECUTABLE=/usr/bin/python3 "${launcher[@]}" >/dev/null
cmake --build "$BUILD" -j "$JOBS"
cd "$BUILD"
# Any report fails the test that caused it: UBSan aborts instead of printing and going on.
# Third-party headers' reports are suppressed one by one in scripts/ubsan.supp (each says why).
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1:suppressions=$ROOT/scripts/ubsan.supp}
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
