#include "methods/register.h"

#include "core/method.h"
#include "methods/pipeline.h"
#include "sampling/dynamic_sampling.h"

namespace scatterlab {

const std::vector<MethodDesc>& builtinMethods() {
  // adaptive's initial samples: measured best at <= 4000 samples on the fidelity scenes
  // (docs/fidelity.md §6). gradient, which never splits, takes as many as adaptive may end
  // with (its budget cap), never more: better than 2000 on every fidelity scene but lamp_puff
  // (docs/fidelity.md §13).
  constexpr long long kExtendedCount = 2000;
  constexpr long long kGradientCount = kBudgetCap;
  static const std::vector<MethodDesc> table = {
      {.name = "exact",
       .summary = "per-pixel march, transmittance to every light traced at each step (reference)",
       .integrator = "exact",
       .integratorSelectable = false},
      {.name = "per-voxel",
       .summary = "S traced at every voxel, then marched (the paper's baseline)",
       .reconstruction = "per-voxel",
       .integrator = "ray-marcher"},
      {.name = "gradient",
       .summary = "samples with S and ∇S, first-order Taylor splatting (paper Eq. 4)",
       .sampler = true,
       .reconstruction = "gradient",
       .wholeSceneFallback = "per-voxel",
       .integrator = "ray-marcher",
       .extended = true,
       .extendedSampler = {.type = "jittered", .count = kGradientCount, .atMost = true}},
      {.name = "rbf",
       .summary = "samples with S, normalised RBF interpolation (Zhou et al. 2007)",
       .sampler = true,
       .reconstruction = "rbf",
       .integrator = "ray-marcher"},
      {.name = "nearest",
       .summary = "samples with S, nearest covering sample",
       .sampler = true,
       .reconstruction = "nearest",
       .integrator = "ray-marcher"},
      {.name = "adaptive",
       .summary = "gradient with dynamic sampling (paper Sec. 5: Eq. 5 error, grid splitting)",
       .sampler = true,
       .refiner = "dynamic",
       .reconstruction = "gradient",
       .wholeSceneFallback = "per-voxel",
       .integrator = "ray-marcher",
       .extended = true,
       .extendedSampler = {.type = "grid", .count = kExtendedCount}},
      {.name = "light-space-march",
       .summary = "per-pixel march with shadow-map visibility and interleaved sampling (Tóth & "
                  "Umenhoffer 2009)",
       .integrator = "light-space-march",
       .integratorSelectable = false},
      {.name = "radial-blur",
       .summary = "occlusion pre-pass and screen-space radial blur towards each light (Mitchell, "
                  "GPU Gems 3 ch. 13)",
       .integrator = "radial-blur",
       .integratorSelectable = false},
      // The per-pixel competitors (docs/competitors.md): no samples, no radiance volume.
      {.name = "jittered-march",
       .summary = "per-pixel march, fixed steps per ray, jittered offsets, optional low-res + "
                  "bilateral upsampling (Bevy/Unity)",
       .integrator = "jittered-march",
       .integratorSelectable = false},
      {.name = "froxel",
       .summary = "frustum-aligned grid: in-scattering per froxel, front-to-back accumulation, "
                  "one lookup per pixel (Wronski 2014, Hillaire 2015)",
       .integrator = "froxel",
       .integratorSelectable = false},
  };
  return table;
}

void registerMethods() {
  for (const MethodDesc& d : builtinMethods()) {
    MethodEntry e;
    e.summary = d.summary;
    e.keyDocs = methodKeyTable(d);
    for (const KeyDoc& row : e.keyDocs) e.keys.emplace_back(row.name);
    e.runsOn = [d](Backend b) { return pipelineRunsOn(d, b); };
    e.create = [d](Params& render, const Scene& scene, Backend b, const std::string& note) {
      return makePipelineMethod(d, render, scene, b, note);
    };
    methods().add(d.name, std::move(e));
  }
}

}  // namespace scatterlab
