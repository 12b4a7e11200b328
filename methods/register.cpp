#include "methods/register.h"

#include "core/method.h"
#include "methods/pipeline.h"

namespace scatterlab {

const std::vector<MethodDesc>& builtinMethods() {
  // name, summary, sampler, refiner, reconstruction, integrator, render.integrator selectable,
  // extensions on by default, the sampler without render.sampler when they are on (measured
  // best at <= 4000 samples on the fidelity scenes: docs/fidelity.md)
  static const std::vector<MethodDesc> table = {
      {"exact", "per-pixel march, transmittance to every light traced at each step (reference)",
       false, "", "", "exact", false, false, ""},
      {"per-voxel", "S traced at every voxel, then marched (the paper's baseline)", false, "",
       "per-voxel", "ray-marcher", true, false, ""},
      {"gradient", "samples with S and ∇S, first-order Taylor splatting (paper Eq. 4)", true, "",
       "gradient", "ray-marcher", true, /*extended=*/true,
       R"({"type": "jittered", "count": 2000})"},
      {"rbf", "samples with S, normalised RBF interpolation (Zhou et al. 2007)", true, "", "rbf",
       "ray-marcher", true, false, ""},
      {"nearest", "samples with S, nearest covering sample", true, "", "nearest", "ray-marcher",
       true, false, ""},
      {"adaptive", "gradient with dynamic sampling (paper Sec. 5: Eq. 5 error, grid splitting)",
       true, "dynamic", "gradient", "ray-marcher", true, /*extended=*/true,
       R"({"type": "grid", "count": 2000})"},
      {"light-space-march",
       "per-pixel march with shadow-map visibility and interleaved sampling (Tóth & Umenhoffer "
       "2009)",
       false, "", "", "light-space-march", false, false, "", /*viewMarch=*/false},
      {"radial-blur",
       "occlusion pre-pass and screen-space radial blur towards each light (Mitchell, GPU Gems "
       "3 ch. 13)",
       false, "", "", "radial-blur", false, false, ""},
      // The per-pixel competitors (docs/competitors.md): no samples, no radiance volume.
      {"jittered-march",
       "per-pixel march, fixed steps per ray, jittered offsets, optional low-res + bilateral "
       "upsampling (Bevy/Unity)",
       false, "", "", "jittered-march", false, false, ""},
      {"froxel",
       "frustum-aligned grid: in-scattering per froxel, front-to-back accumulation, one "
       "lookup per pixel (Wronski 2014, Hillaire 2015)",
       false, "", "", "froxel", false, false, ""},
  };
  return table;
}

void registerMethods() {
  for (const MethodDesc& d : builtinMethods()) {
    MethodEntry e;
    e.summary = d.summary;
    e.keys = methodKeys(d);
    e.runsOn = [d](Backend b) { return pipelineRunsOn(d, b); };
    e.create = [d](Params& render, const Scene& scene, Backend b, const std::string& note) {
      return makePipelineMethod(d, render, scene, b, note);
    };
    methods().add(d.name, std::move(e));
  }
}

}  // namespace scatterlab
