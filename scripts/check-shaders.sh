#!/usr/bin/env bash
# Every GLSL program text the GPU code compiled, checked by a second compiler: the Khronos
# reference front end (Debian's glslang-tools, `glslangValidator`). Mesa's llvmpipe is the only
# driver the tests run on; a text it accepts that the GLSL 4.50 specification does not (an
# implicit conversion, a redeclaration, a missing `#endif` in an unused variant) would fail on
# another vendor's driver. The texts come from a run with SCATTERLAB_GPU_SHADER_DUMP=DIR
# (gpu/gl.cpp: each text that compiled, once, as DIR/<hash>.<comp|vert|frag>); scripts/test.sh
# sets it for the whole suite, so the variants checked are those the tests use.
# Usage: scripts/check-shaders.sh DIR
# Exit 0: all pass; 1: some fail (their logs printed); 2: usage, no texts, no validator.
set -uo pipefail
DIR=${1:-}
[[ -n $DIR && -d $DIR ]] || { echo "usage: scripts/check-shaders.sh DIR (a SCATTERLAB_GPU_SHADER_DUMP folder)" >&2; exit 2; }
command -v glslangValidator >/dev/null ||
  { echo "check-shaders: glslangValidator not found (Debian: apt-get install glslang-tools)" >&2; exit 2; }
shopt -s nullglob
texts=("$DIR"/*.comp "$DIR"/*.vert "$DIR"/*.frag)
((${#texts[@]})) || { echo "check-shaders: no shader texts in $DIR" >&2; exit 2; }
# One line per failing text: its log, flattened (glslangValidator prints the file name first).
failures=$(printf '%s\0' "${texts[@]}" | xargs -0 -P "${SCATTERLAB_JOBS:-2}" -n 16 sh -c '
  for f; do
    log=$(glslangValidator "$f" 2>&1) || printf "%s: %s\n" "$f" "$(printf "%s" "$log" | tr "\n" " ")"
  done' sh)
if [[ -n $failures ]]; then
  printf '%s\n' "$failures"
  echo "check-shaders: $(printf '%s\n' "$failures" | wc -l) of ${#texts[@]} shader texts fail glslangValidator ($(glslangValidator --version | head -n 1))" >&2
  exit 1
fi
echo "check-shaders: all ${#texts[@]} shader texts pass glslangValidator ($(glslangValidator --version | head -n 1))"
