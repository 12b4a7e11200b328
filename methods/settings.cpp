#include "methods/settings.h"

#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "sampling/dynamic_sampling.h"

namespace scatterlab {

const std::vector<KeyDoc>& pipelineKeys() {
  static const std::vector<KeyDoc> keys = {
      {"paper", "bool", "false", "true, false",
       "the paper's algorithm exactly: every extension off; methods with samples"},
      {"factor_lights", "bool", "true for gradient and adaptive, else false (false with paper)",
       "true, false",
       "interpolate S divided by the lights' analytic unshadowed source radiance, multiply it "
       "back at each march step (singular lights); methods with samples"},
      {"log_space", "bool", "false", "true, false (true needs factor_lights)",
       "interpolate ln V (a light-weighted optical depth, nearly linear) and store exp of it; "
       "dynamic sampling then measures its error on V; methods with samples"},
      {"occlusion_weights", "bool", "false", "true, false",
       "Eq. 4 weights times exp(−σt·τ) of the segment sample → voxel: no sample contributes "
       "across a dense occluder; gradient reconstruction"},
      {"bounded_taylor", "bool", "true (false with paper)", "true, false",
       "clamp each sample's Taylor estimate to the known range of what is interpolated (V in "
       "[0, 1], ln V <= 0, S >= 0) before weighting; gradient reconstruction"},
      {"march_step", "number", "one voxel edge", "(diag·1e-6, diag], diag = box diagonal",
       "view-ray step (world units)"},
      {"min_transmittance", "number", "1e-6", "[0, 1]",
       "a view ray stops when its transmittance falls below this"},
      {"delta1", "number", "one voxel edge", "(diag·1e-6, diag]",
       "volume-tracing step towards the lights (the paper's Δ1)"},
      {"delta2", "number", "one voxel edge", "(diag·1e-6, diag]",
       "central-difference step of ∇S (the paper's Δ2); methods with samples"},
      {"radiance_resolution", "int or [nx,ny,nz]", "medium.resolution",
       "1…4096 per axis, integers, at most 512³ voxels",
       "voxels of the source-radiance volume; methods that build one"},
      {"slicing", "string", "ray-steps", "ray-steps, view-planes",
       "GPU marcher's layers: each ray's own steps (= CPU samples) or the paper's view-aligned "
       "slabs; accepted and reported unused on the CPU"},
      {"evaluator", "string", "volume-tracer", "a registered radiance evaluator",
       "how S and ∇S are computed at the samples; methods with samples"},
      {"integrator", "string", "ray-marcher", "a registered integrator",
       "how the image is marched from the volumes; methods with a radiance volume"},
  };
  return keys;
}

namespace {

/// Bounds on marching work, checked before a render starts (docs/reliability.md): view-ray
/// steps (pixels × spp × diagonal / march_step), and light-march steps taken per view step
/// (exact) or per voxel (per-voxel). 1e10 view steps take minutes on a few cores.
constexpr double kMaxViewSteps = 1e10;
constexpr double kMaxLightSteps = 1e12;

std::string sci(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

void checkWork(Params& p, const Scene& scene, const MethodDesc& d, const PipelineSettings& s) {
  const double diag = glm::length(glm::dvec3(scene.medium.bounds.extent()));
  const Camera& c = scene.camera;
  const double rays = double(c.width) * c.height * c.spp;
  const double perRay = std::ceil(diag / s.march.step);
  const double view = rays * perRay;
  const std::string size = std::to_string(c.width) + "x" + std::to_string(c.height) + " pixels x " +
                           std::to_string(c.spp) + " spp";
  if (view > kMaxViewSteps)
    throw LimitError("'" + p.keyPath("march_step") + "': a step of " + sci(s.march.step) +
                     " gives " + sci(perRay) + " steps per view ray (box diagonal " + sci(diag) +
                     "), " + sci(view) + " steps for " + size + ", above the bound of " +
                     sci(kMaxViewSteps) + "; use a longer step or a smaller image");
  const double perLight =
      std::ceil(diag / s.delta1) * double(std::max<size_t>(1, scene.lights.size()));
  double light = 0;
  std::string what;
  if (d.integrator == "exact") {
    light = view * perLight;
    what = "at every one of " + sci(view) + " view steps";
  } else if (d.reconstruction == "per-voxel") {
    const IVec3 r = s.radianceResolution;
    const double voxels = double(r.x) * r.y * r.z;
    light = voxels * perLight;
    what = "at every one of " + sci(voxels) + " voxels";
  }
  if (light > kMaxLightSteps)
    throw LimitError("'" + p.keyPath("delta1") + "': a step of " + sci(s.delta1) + " gives " +
                     sci(perLight) + " light-march steps " + what + ", " + sci(light) +
                     " in all, above the bound of " + sci(kMaxLightSteps) +
                     "; use a longer step, a smaller image or volume");
}

}  // namespace

PipelineSettings parsePipelineSettings(Params& p, const Scene& scene, const MethodDesc& d) {
  PipelineSettings s;
  const float voxel = scene.medium.voxelSize();
  const Interval steps = stepRange(glm::length(scene.medium.bounds.extent()));
  s.march.step = p.real("march_step", voxel, steps);
  s.march.minTransmittance = p.real("min_transmittance", 1e-6, Interval::closed(0, 1));
  s.delta1 = p.real("delta1", voxel, steps);
  if (d.sampler) {
    s.delta2 = p.real("delta2", voxel, steps);
    s.paper = p.boolean("paper", false);
    s.factorLights = p.boolean("factor_lights", d.extended && !s.paper);
    if (s.paper && s.factorLights)
      p.fail("factor_lights", "is an extension; it cannot be true with render.paper = true");
    // Off by default (measured, docs/fidelity.md): with adaptive it wins on dense self-shadowing
    // smoke (chimney, smoke1) and loses with lamps inside fog and, badly, at the hard shadows
    // of scene objects (window: 3.4 % -> 10.9 %), where ln V falls to ln kMinV.
    s.logSpace = p.boolean("log_space", false);
    // Off by default: measured (docs/fidelity.md) a clear win with adaptive on occluders (the
    // perforated sheet, the chimney trail) but 3-30x the frame time and worse on smoke1.
    s.occlusionWeights = p.boolean("occlusion_weights", false);
    if (s.paper && s.occlusionWeights)
      p.fail("occlusion_weights", "is an extension; it cannot be true with render.paper = true");
    s.boundedTaylor = p.boolean("bounded_taylor", !s.paper);
    if (s.paper && s.boundedTaylor)
      p.fail("bounded_taylor", "is an extension; it cannot be true with render.paper = true");
    if (s.logSpace && !s.factorLights)
      p.fail("log_space", "interpolates ln V of factor_lights; it needs factor_lights = true");
  }
  if (d.radianceVolume()) {
    s.radianceResolution = p.resolution("radiance_resolution", scene.medium.resolution,
                                        sizeof(Vec3), "the source-radiance volume (RGB float)");
    s.slicingGiven = p.has("slicing");
    s.slicing = p.choice("slicing", {"ray-steps", "view-planes"}, "ray-steps") == "ray-steps"
                    ? Slicing::RaySteps
                    : Slicing::ViewPlanes;
  }
  checkWork(p, scene, d, s);
  return s;
}

std::vector<std::string> methodKeys(const MethodDesc& d) {
  std::vector<std::string> k = {"march_step", "min_transmittance", "delta1"};
  if (d.sampler)
    k.insert(k.end(), {"delta2", "paper", "factor_lights", "log_space", "occlusion_weights",
                       "bounded_taylor", "sampler", "evaluator"});
  if (d.radianceVolume()) k.insert(k.end(), {"radiance_resolution", "slicing"});
  if (d.integratorSelectable) k.push_back("integrator");
  if (!d.refiner.empty())
    for (const KeyDoc& key : dynamicSamplingKeys()) k.emplace_back(key.name);
  return k;
}

std::unique_ptr<Sampler> makeSampler(Params& p, const Scene& scene, std::string& type,
                                     const std::string& extendedDefault) {
  const bool hasGaussians = scene.medium.density && scene.medium.density->gaussians();
  const Json defaultSampler = !extendedDefault.empty() ? Json::parse(extendedDefault)
                              : hasGaussians           ? Json{{"type", "gaussian-centres"}}
                                                       : Json{{"type", "jittered"}, {"count", 512}};
  const bool given = p.has("sampler");
  Params sp = given ? p.child("sampler") : Params(defaultSampler, p.keyPath("sampler"));
  if (!given) p.allow("sampler");
  type = sp.string("type", defaultSampler["type"].get<std::string>());
  std::unique_ptr<Sampler> sampler = samplers().get(type, sp.keyPath("type"))(sp, scene);
  sp.finish();
  return sampler;
}

}  // namespace scatterlab
