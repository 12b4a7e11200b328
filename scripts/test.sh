#!/usr/bin/env bash
# Sets everything up (scripts/setup.sh), installs what only the tests need when it is missing
# (Debian's chromium, chromium-driver, python3-selenium for the browser test of report.html:
# ReportHtml.* skips without them; glslang-tools for the shader check; a plain build needs
# none), runs the whole test suite with ctest, then checks every shader text the suite compiled
# with the Khronos reference compiler (scripts/check-shaders.sh), then runs the GPU tests once
# more with a GPU's approximate built-ins simulated (SCATTERLAB_GPU_IMPRECISE=4, gpu/shaders.h:
# exp, log, sqrt, normalize, ... 4 ulps off), so that no CPU ≡ GPU tolerance holds only by
# llvmpipe's precision (~75 s).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh build

TEST_PACKAGES=(chromium chromium-driver python3-selenium glslang-tools)
missing=()
for p in "${TEST_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "scatterlab test: installing ${missing[*]} (what only the tests use)"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

rm -rf build/shader-texts && mkdir -p build/shader-texts
(cd build && SCATTERLAB_GPU_SHADER_DUMP="$PWD/shader-texts" \
  ctest --output-on-failure -j "${SCATTERLAB_JOBS:-2}" --timeout 900)
scripts/check-shaders.sh build/shader-texts
# Mesa's shader cache on for it: the run above checked the texts for warnings.
(cd build && SCATTERLAB_GPU_IMPRECISE=4 MESA_SHADER_CACHE_DISABLE=false \
  ctest --output-on-failure -j "${SCATTERLAB_JOBS:-2}" --timeout 900 -R Gpu)
