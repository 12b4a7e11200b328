#!/usr/bin/env bash
# Builds the libFuzzer targets in fuzz/ with clang-14 (ASan + UBSan + libFuzzer) into
# build-fuzz/ and runs each for SECONDS (default 60), seeded from the repository's JSON files.
# Usage: scripts/fuzz.sh [SECONDS]. A crash leaves crash-* in build-fuzz/TARGET/ and exits 1.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_EACH=${1:-60}
OUT=build-fuzz
mkdir -p "$OUT"
CXX=${CXX_FUZZ:-clang++-14}
FLAGS=(-std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined
  -I. -I/usr/include/glm)
status=0
for src in fuzz/fuzz_*.cpp; do
  name=$(basename "$src" .cpp)
  mkdir -p "$OUT/$name/corpus"
  # The strict JSON reader and Params are self-contained in core/params.cpp: compiled here
  # with coverage, not linked from the GCC-built library.
  "$CXX" "${FLAGS[@]}" "$src" core/params.cpp -o "$OUT/$name/$name"
  seeds=("$OUT/$name/seeds")
  mkdir -p "${seeds[0]}"
  if [ "$name" = fuzz_json ]; then
    find data tests -name '*.json' -size -64k -exec cp {} "${seeds[0]}/" \;
  else
    printf 'camera.position=[1e39,0,0]' >"${seeds[0]}/a"
    printf 'a.b.c={"x":[1,2,{"y":null}]}' >"${seeds[0]}/b"
    printf 'lights=[{"type":"point"}]' >"${seeds[0]}/c"
  fi
  # Inputs that once crashed a target stay in its seeds (fuzz/regressions/TARGET_*).
  find fuzz/regressions -name "${name}_*" -exec cp {} "${seeds[0]}/" \;
  echo "== $name: ${SECONDS_EACH} s"
  (cd "$OUT/$name" && ./"$name" -max_total_time="$SECONDS_EACH" -max_len=65536 -rss_limit_mb=2048 \
    -print_final_stats=1 corpus seeds 2>&1 | grep -E "stat::number_of_executed_units|Done|ERROR|crash-" ) ||
    status=1
  ls "$OUT/$name"/crash-* >/dev/null 2>&1 && status=1
done
exit $status
