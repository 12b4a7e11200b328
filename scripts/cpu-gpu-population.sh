#!/usr/bin/env bash
# CPU ≡ GPU on scenes nobody tuned for: the 60 scenes of the population (docs/fidelity.md,
# "Population of scenes") rendered by per-voxel, gradient and adaptive at their defaults on both
# backends (data/experiments/population_cpu_gpu.json), then every GPU image compared with the
# CPU's by `scatterlab compare` (relative L2; issue 33's bound: 1e-4), and the two runs' sample
# counts and whole-scene fallback decisions (`voxels_instead`), which must be equal: one
# function decides for both backends. Scenes with objects (the occluder family) are listed
# apart and held to neither: the GPU looks their shadows up in shadow maps where the CPU traces
# rays (docs/objects.md, "CPU ≡ GPU": several percent along shadow edges, and so other errors
# for dynamic sampling to split on). The tests check CPU ≡ GPU on small scenes picked for each
# feature; this checks it on twelve families of random scenes, on whatever GPU runs it.
# Usage: scripts/cpu-gpu-population.sh [OUT_DIR] [CONFIG]   (default cpu-gpu-population/ and
#   data/experiments/population_cpu_gpu.json; after scripts/setup.sh, or through the GPU bundle
#   like scripts/gpu-report.sh). Resumes where OUT_DIR has runs already (the harness's resume).
# Writes OUT_DIR/cpu_gpu.txt (one line per scene and method, worst first, with the relative L2
# masked next to each light beside it: a pixel whose ray passes a point light within a
# thousandth of the scene holds most of an image's L2, and a GPU's rounding of the ray there
# shows; the bound is on the unmasked figure) and the experiment's own output; exit 1 when a run
# failed, a pair differs by more than the bound or in its samples or decision. On llvmpipe (2
# cores) the GPU half takes ~40 minutes: llvmpipe's times are CPU times; only the comparison
# means something there. With SCATTERLAB_GPU_IMPRECISE=4 (gpu/shaders.h) it shows what a GPU's
# rounding does to the same pairs (docs/gpu.md, "A GPU's arithmetic, simulated").
set -uo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-cpu-gpu-population}
CONFIG=${2:-data/experiments/population_cpu_gpu.json}
BOUND=1e-4
if [[ -x build/bin/scatterlab ]]; then CLI=build/bin/scatterlab; else CLI=$(command -v scatterlab); fi
[[ -n ${CLI:-} ]] || { echo "cpu-gpu-population: build first (scripts/setup.sh)" >&2; exit 2; }
status=0
"$CLI" experiment "$CONFIG" -o "$OUT" -q --no-plots --no-progress || status=1

# A top-level key of a run record ("  \"key\": value,") or one of its stats ("    ...").
field() { sed -n "s/^$2\"$3\": \([^,]*\),\{0,1\}$/\1/p" "$1" | head -n 1; }
# compare's options per scene name, read from CONFIG once: the scene file and the config's --set
# overrides (for the relative L2 with the pixels next to each light masked, docs/metrics.md).
declare -A sceneOptions=()
while IFS=$'\t' read -r name options; do
  sceneOptions[$name]=$options
done < <(python3 - "$CONFIG" <<'PY'
import json, os, sys
config = sys.argv[1]
doc = json.load(open(config))
sets = "".join(" --set " + kv for kv in doc.get("set", []))
for s in doc.get("scenes", []):
    f = s["file"] if isinstance(s, dict) else s
    name = os.path.splitext(os.path.basename(f))[0]
    print(name + "\t--scene " + os.path.join(os.path.dirname(config), f) + sets)
PY
)
max() { awk -v r="$1" -v w="$2" 'BEGIN { print (r > w ? r : w) }'; }
pairs=0 over=0 differ=0 worst=0 worstMasked=0 objects=0 worstObjects=0 table=$OUT/cpu_gpu.txt.tmp
: >"$table"
: >"$table.objects"
for gpu in "$OUT"/images/*-gpu.exr; do
  [[ -e $gpu ]] || continue
  id=$(basename "$gpu" -gpu.exr) cpu=${gpu%-gpu.exr}-cpu.exr
  [[ -e $cpu ]] || continue
  # shellcheck disable=SC2086  # options and values without spaces, split on purpose
  cmp=$("$CLI" compare --json "$gpu" "$cpu" ${sceneOptions[${id%%__*}]:-})
  rel=$(sed -n 's/^ *"rel_l2": \([^,]*\),$/\1/p' <<<"$cmp")
  masked=$(sed -n 's/^ *"masked_rel_l2": \([^,]*\),$/\1/p' <<<"$cmp")
  [[ -n $masked ]] && masked=$(printf '%.3e' "$masked")
  [[ -n $rel ]] || { echo "cpu-gpu-population: cannot compare $id" >&2; status=1; continue; }
  gr=$OUT/runs/$id-gpu.json cr=$OUT/runs/$id-cpu.json
  gs=$(field "$gr" '  ' samples) cs=$(field "$cr" '  ' samples)
  gv=$(field "$gr" '    ' voxels_instead) cv=$(field "$cr" '    ' voxels_instead)
  note=""
  # Objects: the sampled methods' records carry the shadow_map settings, every GPU record the
  # stage "shadow maps"; not held to the bound.
  if grep -q -e '"shadow_map": {' -e '"shadow maps": ' "$gr"; then
    note=" (objects: GPU shadow maps${gs:+; GPU samples $gs})"
    objects=$((objects + 1)) worstObjects=$(max "$rel" "$worstObjects")
  else
    if [[ $gs != "$cs" || $gv != "$cv" ]]; then
      note=" DIFFERS: samples $cs (cpu) / $gs (gpu), per-voxel instead ${cv:-—} / ${gv:-—}"
      differ=$((differ + 1))
    fi
    awk -v r="$rel" -v b="$BOUND" 'BEGIN { exit !(r > b || r != r) }' && over=$((over + 1))
    worst=$(max "$rel" "$worst")
    [[ -n $masked ]] && worstMasked=$(max "$masked" "$worstMasked")
    pairs=$((pairs + 1))
  fi
  printf '%.3e  %-28s masked %s; samples %s, per-voxel instead %s%s\n' "$rel" "$id" \
    "${masked:-—}" "${cs:-—}" "${cv:-—}" "$note" >>"$table${note:+.objects}"
done
{
  echo "CPU vs GPU, relative L2 of the GPU image against the CPU's ($CONFIG, $("$CLI" info --gpu 2>/dev/null | head -n 1))"
  sort -g -r "$table"
  sort -g -r "$table.objects"
  printf '%d pairs; worst %.3e (masked: %.3e); above %s: %d; samples or decision differ: %d' \
    "$pairs" "$worst" "$worstMasked" "$BOUND" "$over" "$differ"
  printf '; with objects (shadow maps, apart): %d, worst %.3e\n' "$objects" "$worstObjects"
} >"$OUT/cpu_gpu.txt"
rm -f "$table" "$table.objects"
head -n "$((1 + (pairs < 10 ? pairs : 10)))" "$OUT/cpu_gpu.txt"
tail -n 1 "$OUT/cpu_gpu.txt"
[[ $pairs -gt 0 && $over -eq 0 && $differ -eq 0 ]] || status=1
exit $status
