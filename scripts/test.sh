#!/usr/bin/env bash
# Sets everything up (scripts/setup.sh), installs what the browser test of report.html needs
# when it is missing (Debian's chromium, chromium-driver, python3-selenium: the test
# ReportHtml.* skips without them, a plain build does not need them), then runs the whole test
# suite with ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh build

BROWSER_PACKAGES=(chromium chromium-driver python3-selenium)
missing=()
for p in "${BROWSER_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "scatterlab test: installing ${missing[*]} (the browser test of report.html)"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

cd build
ctest --output-on-failure -j "${SCATTERLAB_JOBS:-2}" --timeout 900
