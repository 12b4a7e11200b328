#!/usr/bin/env bash
# One command for a GPU report (issue 33): where a machine with a GPU stands.
#   1. the device (scatterlab info --gpu);
#   2. steady frames (a Renderer, a light moved each frame, the image left on the GPU: what an
#      engine waits for) and cold frames (a new method per frame, image read back: what
#      `scatterlab render` and the harness draw) of gradient (paper and defaults), per-voxel and
#      adaptive (paper and defaults), 128³ and 256³, 1 and 64 lights, the compute pipeline and,
#      for the paper's gradient, the raster one — wall ms, GPU ms (timer queries), host waits;
#   3. the GPU stage benchmarks (bench/bench_gpu.cpp);
#   test_gpu runs first, after the device: whether the GPU draws right matters more than how fast,
#   and a device call is cut at 10 minutes (each step has its own timeout; together 540 s).
# Usage: scripts/gpu-report.sh [OUT_DIR]   (default gpu-report/; after scripts/setup.sh).
#        scripts/gpu-report.sh --table2 [OUT_DIR]   the harness's GPU Table 2 instead
#   (data/experiments/table2_gpu.json: every method cold and steady at 800×600 over the plume's
#   resolutions and lights and the shaft's spot lights, errors against the CPU's per-voxel and
#   exact; ~68 runs, meant as a second device call of its own). Its images stay in
#   out/table2_gpu (a rerun on the same machine resumes there); OUT_DIR/table2_gpu/ gets
#   results.json, results.csv and report.md. Then, here: python3 scripts/results_md.py
#   --table2-gpu OUT_DIR/table2_gpu writes docs/RESULTS.md's "GPU Table 2". TABLE2_CONFIG names
#   another config (a smaller one, to check the plumbing on llvmpipe).
# Both end with scripts/gpu-targets.py (issues 33 and 34's targets, met or missed) where the
# machine has python3; run it here on OUT_DIR otherwise.
# On a machine without packages: ../shared/tools/gpu-bundle.sh here, then on that machine
#   bash .gpu-bundle/run.sh bash scripts/gpu-report.sh
#   (where the bundle's run.sh sets B= to a relative path, make it absolute first: the links it
#   makes to build/bin are relative to where they lie, and the CLI tests then find no binary.)
# Then, as a second device call: scripts/cpu-gpu-population.sh (CPU ≡ GPU on the population's 60
# scenes, every method; its CPU half a few minutes on 16 cores).
# Writes OUT_DIR/device.txt, frames.json (+ frames.txt), stages.json (+ stages.txt),
# test_gpu.txt, and prints a summary. Took 2.5 minutes on an H200 (2026-11-27); set
# SCATTERLAB_GPU_BENCH_ITERS to change the iterations (default 30). On llvmpipe use
# SCATTERLAB_GPU_BENCH_ITERS=1: its times are CPU times, only the counts mean something.
set -uo pipefail
cd "$(dirname "$0")/.."
TABLE2=0
[[ ${1:-} == --table2 ]] && { TABLE2=1; shift; }
OUT=${1:-gpu-report}
mkdir -p "$OUT"
bin() {  # a tool from build/bin, else from PATH (the GPU bundle's wrappers)
  if [[ -x build/bin/$1 ]]; then echo "build/bin/$1"; else command -v "$1"; fi
}
CLI=$(bin scatterlab) BENCH=$(bin scatterlab_bench) TESTS=$(bin test_gpu)
[[ -n $CLI && -n $BENCH && -n $TESTS ]] || { echo "gpu-report: build first (scripts/setup.sh)" >&2; exit 2; }
export SCATTERLAB_GPU_BENCH_ITERS=${SCATTERLAB_GPU_BENCH_ITERS:-30}
status=0

targets() {  # issues 33 and 34's targets from what OUT holds
  if command -v python3 >/dev/null; then
    echo "== targets (scripts/gpu-targets.py $*)"
    python3 scripts/gpu-targets.py "$@" | tee "$OUT/targets.txt"
  else
    echo "== no python3 here: run python3 scripts/gpu-targets.py $* on the copy of $OUT"
  fi
}

echo "== device"
"$CLI" info --gpu | tee "$OUT/device.txt" || status=1
echo "load average: $(cat /proc/loadavg)" | tee -a "$OUT/device.txt"

if [[ $TABLE2 == 1 ]]; then
  echo "== GPU Table 2 (the harness, data/experiments/table2_gpu.json)"
  WORK=out/table2_gpu
  timeout 540 "$CLI" experiment "${TABLE2_CONFIG:-data/experiments/table2_gpu.json}" -o "$WORK" -q --no-plots \
    --no-progress || status=1
  mkdir -p "$OUT/table2_gpu"
  for f in results.json results.csv report.md log.txt; do
    [[ -f $WORK/$f ]] && cp "$WORK/$f" "$OUT/table2_gpu/"
  done
  [[ -f $OUT/table2_gpu/results.json ]] && targets --table2 "$OUT/table2_gpu" \
    $([[ -f $OUT/frames.json ]] && echo --report "$OUT")
else
  echo "== test_gpu (compute and raster pipelines)"
  # Validated from the start, as ctest runs every GPU test (tests/CMakeLists.txt): installed
  # only by the first GpuValidate test, it would find programs already built unchecked, and
  # Mesa's shader cache still on.
  SCATTERLAB_GPU_VALIDATE=1 timeout 150 "$TESTS" --gtest_brief=1 2>&1 | tee "$OUT/test_gpu.txt"
  [[ ${PIPESTATUS[0]} -eq 0 ]] || status=1

  echo "== frames (steady and cold; ms per frame, gpu_ms, host_waits)"
  timeout 270 "$BENCH" --benchmark_filter='BM_Gpu(Steady|Cold)Frame' \
    --benchmark_out="$OUT/frames.json" --benchmark_out_format=json \
    --benchmark_counters_tabular=true | tee "$OUT/frames.txt" || status=1

  echo "== GPU stage benchmarks"
  timeout 120 "$BENCH" --benchmark_filter='BM_Gpu(DensitySplat|VolumeTracer512|GradientSplat512|PerVoxel|ViewMarch800x600|SliceMarch800x600|GradientPipeline512|AdaptivePipeline)' \
    --benchmark_out="$OUT/stages.json" --benchmark_out_format=json | tee "$OUT/stages.txt" || status=1

  targets --report "$OUT"
fi
echo "== written to $OUT/ (status $status)"
exit $status
