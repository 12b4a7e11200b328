#!/usr/bin/env bash
# Builds the libFuzzer targets in fuzz/ with clang-14 (ASan + UBSan + libFuzzer) into
# build-fuzz/ and runs each for SECONDS (default 60), seeded from the repository's files
# (JSON from data/ and tests/; .sog, .vdb and .exr written by the GCC build in BUILD, default
# build/, and data/vdb). Usage: scripts/fuzz.sh [SECONDS] [TARGET...]. A crash
# leaves crash-* in build-fuzz/TARGET/ and exits 1, and so does an input that runs longer than
# 60 s (timeout-*) or grows the process past 2 GiB resident (oom-*). Objects are compiled
# through ccache (when installed), two at a time, into build-fuzz/TARGET/obj/. SECONDS = build:
# only build the targets.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_EACH=${1:-60}
shift || true
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=(fuzz_json fuzz_set fuzz_sog fuzz_vdb fuzz_exr fuzz_compare fuzz_scene)
OUT=build-fuzz
# libFuzzer reports allocations above its -rss_limit_mb (2 GiB): the library's own memory limit
# is set below it, so a size the limit refuses is an error, not a finding.
export SCATTERLAB_MEMORY_LIMIT=${SCATTERLAB_MEMORY_LIMIT:-64M}
CLI=${BUILD:-build}/bin/scatterlab
# .vdb files are parsed in scatterlab's reader program (media/vdb.h), the build tree's.
export SCATTERLAB_VDB_READER=${SCATTERLAB_VDB_READER:-$PWD/${BUILD:-build}/bin/scatterlab-vdb-reader}
mkdir -p "$OUT"
CXX=${CXX_FUZZ:-clang++-14}
CCACHE=$(command -v ccache || true)
# Objects get libFuzzer's coverage (fuzzer-no-link); the link adds libFuzzer's main.
FLAGS=(-std=c++20 -O1 -g -fsanitize=fuzzer-no-link,address,undefined
  -fno-sanitize-recover=undefined -I. -I/usr/include/glm -I/usr/include/eigen3
  -DOPENVDB_ABI_VERSION_NUMBER=10 -DOPENVDB_USE_DELAYED_LOADING "-DFUZZ_SOURCE_DIR=\"$PWD\"")
LINK=(-fsanitize=fuzzer,address,undefined)
status=0
# Sources compiled into each target with coverage (the code under test; the libraries it
# calls, OpenVDB, OpenEXR, TBB, are Debian's, without coverage).
declare -A SOURCES=(
  [fuzz_json]="core/params.cpp core/limits.cpp"
  [fuzz_set]="core/params.cpp core/limits.cpp"
  [fuzz_sog]="media/sog.cpp media/procedural.cpp core/density_model.cpp core/atomic_file.cpp core/limits.cpp"
  [fuzz_vdb]="media/vdb.cpp core/density_model.cpp core/atomic_file.cpp core/limits.cpp"
  [fuzz_exr]="core/image.cpp core/atomic_file.cpp core/limits.cpp"
  [fuzz_compare]="core/image.cpp core/metrics.cpp core/camera.cpp core/atomic_file.cpp core/limits.cpp"
  [fuzz_scene]="$(echo core/*.cpp media/*.cpp sampling/*.cpp cpu/*.cpp methods/*.cpp \
    experiment/*.cpp)")
declare -A LIBS=(
  [fuzz_sog]="-ltbb" [fuzz_vdb]="-lopenvdb -ltbb -lImath-3_1"
  [fuzz_exr]="-lOpenEXR-3_1 -lOpenEXRCore-3_1 -lIex-3_1 -lImath-3_1 -lpng"
  [fuzz_compare]="-lOpenEXR-3_1 -lOpenEXRCore-3_1 -lIex-3_1 -lImath-3_1 -lpng"
  [fuzz_scene]="-lopenvdb -ltbb -lOpenEXR-3_1 -lOpenEXRCore-3_1 -lIex-3_1 -lImath-3_1 -lpng -lembree3
    -ltinyobjloader -lpthread")
EXR_INCLUDES=(-I/usr/include/OpenEXR -I/usr/include/Imath)
tmpseeds=$(mktemp -d)
trap 'rm -rf "$tmpseeds"' EXIT
for name in "${TARGETS[@]}"; do
  src=fuzz/$name.cpp
  mkdir -p "$OUT/$name/corpus"
  # One object per source (ccache makes an unchanged one a cache hit), two compilers at once.
  objs=()
  for f in "$src" ${SOURCES[$name]}; do objs+=("$OUT/$name/obj/${f%.cpp}.o"); done
  # shellcheck disable=SC2086
  printf '%s\n' "$src" ${SOURCES[$name]} | xargs -P 2 -I{} sh -c \
    'mkdir -p "$(dirname "$0/obj/$1")" && $2 $3 -c "$1" -o "$0/obj/$(echo "$1" | sed "s/\.cpp$//").o"' \
    "$OUT/$name" {} "$CCACHE $CXX" "${FLAGS[*]} ${EXR_INCLUDES[*]}"
  # shellcheck disable=SC2086
  "$CXX" "${LINK[@]}" "${objs[@]}" -o "$OUT/$name/$name" ${LIBS[$name]:-}
  [ "$SECONDS_EACH" = build ] && continue
  seeds=("$OUT/$name/seeds")
  rm -rf "${seeds[0]}"
  mkdir -p "${seeds[0]}"
  case $name in
    fuzz_json) find data tests -name '*.json' -size -64k -exec cp {} "${seeds[0]}/" \; ;;
    fuzz_scene)  # first byte: even = scene (byte/2 picks the method), odd = experiment config
      for f in data/scenes/*.json $(find tests -name '*.json' -size -64k); do
        grep -q '"file"\|"frames"' "$f" && continue
        b=$(basename "$f" .json)
        { printf '\000'; cat "$f"; } >"${seeds[0]}/s0_$b"
        { printf '\006'; cat "$f"; } >"${seeds[0]}/s3_$b"
        { printf '\016'; cat "$f"; } >"${seeds[0]}/s7_$b"
      done
      for f in data/experiments/*.json; do
        { printf '\001'; cat "$f"; } >"${seeds[0]}/e_$(basename "$f" .json)"
      done ;;
    fuzz_set)
      printf 'camera.position=[1e39,0,0]' >"${seeds[0]}/a"
      printf 'a.b.c={"x":[1,2,{"y":null}]}' >"${seeds[0]}/b"
      printf 'lights=[{"type":"point"}]' >"${seeds[0]}/c" ;;
    fuzz_sog)  # small fits of small exports (the GCC-built tool writes them)
      "$CLI" render data/scenes/glow.json -o "$tmpseeds/g.exr" --density-vdb "$tmpseeds/g.vdb" \
        --set medium.resolution=12 --set camera.width=8 --set camera.height=6 >/dev/null
      "$CLI" fit "$tmpseeds/g.vdb" -o "${seeds[0]}/g8.sog" -n 4 --no-image-check >/dev/null
      "$CLI" fit "$tmpseeds/g.vdb" -o "${seeds[0]}/g16.sog" -n 2 --bits 16 --no-image-check \
        >/dev/null ;;
    fuzz_vdb)
      "$CLI" render data/scenes/glow.json -o "$tmpseeds/v.exr" --density-vdb "${seeds[0]}/g.vdb" \
        --set medium.resolution=6 --set camera.width=8 --set camera.height=6 >/dev/null
      find data/vdb -name '*.vdb' -size -600k -exec cp {} "${seeds[0]}/" \; ;;
    fuzz_exr | fuzz_compare)  # a zip-compressed render, with its Z channel and attributes
      "$CLI" render data/scenes/glow.json -o "${seeds[0]}/a.exr" --set camera.width=6 \
        --set camera.height=4 >/dev/null
      "$CLI" render data/scenes/glow.json -o "${seeds[0]}/z.exr" --set camera.width=5 \
        --set camera.height=3 --depth >/dev/null ;;
  esac
  # Inputs that once crashed a target stay in its seeds (fuzz/regressions/TARGET_*).
  find fuzz/regressions -name "${name}_*" -exec cp {} "${seeds[0]}/" \;
  maxlen=65536
  case $name in fuzz_sog | fuzz_vdb | fuzz_exr | fuzz_compare) maxlen=600000 ;; esac
  echo "== $name: ${SECONDS_EACH} s"
  rm -f "$OUT/$name"/crash-* "$OUT/$name"/timeout-* "$OUT/$name"/oom-*
  # fuzz_vdb: OpenVDB parses in a forked child (media/vdb.cpp). A huge allocation there is a
  # bad_alloc as without ASan (allocator_may_return_null); a memory error there is reported by
  # the child's ASan and libFuzzer handlers, which write a crash-* from the child while this
  # process goes on. Such artifacts are replayed below: only one this process dies on counts.
  opts=${ASAN_OPTIONS:-}
  [ "$name" = fuzz_vdb ] && opts="allocator_may_return_null=1${opts:+:$opts}"
  (cd "$OUT/$name" && ASAN_OPTIONS=$opts ./"$name" -max_total_time="$SECONDS_EACH" -max_len="$maxlen" -rss_limit_mb=2048 \
    -timeout=60 -print_final_stats=1 corpus seeds 2>&1 |
    grep -E "stat::number_of_executed_units|Done|ERROR|crash-|timeout-|oom-|Slowest unit" ) ||
    status=1
  shielded=0
  for c in "$OUT/$name"/crash-* "$OUT/$name"/timeout-* "$OUT/$name"/oom-*; do
    [ -e "$c" ] || continue
    if [ "$name" = fuzz_vdb ] && (cd "$OUT/$name" && ASAN_OPTIONS=$opts ./"$name" -runs=1 \
      -artifact_prefix=replay- "$(basename "$c")" >/dev/null 2>&1); then
      shielded=$((shielded + 1))
      mkdir -p "$OUT/$name/shielded" && mv "$c" "$OUT/$name/shielded/"
    else
      echo "crash: $c"
      status=1
    fi
  done
  rm -f "$OUT/$name"/replay-*
  [ "$shielded" -gt 0 ] && echo "$name: $shielded inputs crashed OpenVDB's reader in the child" \
    "process and were reported as IoError (build-fuzz/$name/shielded/)"
done
exit $status
