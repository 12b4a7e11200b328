#include "methods/settings.h"

#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "core/limits.h"
#include "core/work_limits.h"
#include "media/sog.h"
#include "methods/march_settings.h"
#include "sampling/dynamic_sampling.h"
#include "sampling/samplers.h"

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
      {"fast_march", "bool", "true", "true, false",
       "CPU march: skip blocks of zero density, march in tiles, one fused density + radiance "
       "lookup per step, exact's shadow rays 4 or 8 steps at once (SIMD) (same images within "
       "1e-6); false: the plain march (reference)"},
      {"march_scale", "int", "1", "1, 2, 4 (2 and 4 need camera.spp = 1)",
       "CPU view march at 1/scale of the resolution per axis (one ray per scale × scale pixels), "
       "upsampled depth-aware to full resolution (box entry/exit depths; edges marched in full); "
       "error in docs/benchmarks.md"},
      {"half_float_volumes", "bool", "false", "true, false",
       "fast CPU march: store the fused density + radiance volume in IEEE half (8 instead of 16 "
       "bytes per voxel; error in docs/benchmarks.md); methods with a radiance volume"},
      {"march_simd", "string", "auto", "auto, sse2, avx2",
       "fast CPU march's kernel: auto = avx2 where the CPU has AVX2, FMA and F16C, else sse2 "
       "(same images within 1e-6); methods with a radiance volume"},
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
      {"gpu_pipeline", "string", "compute", "compute, raster",
       "GPU backend: compute shaders (view march one invocation per pixel, radiance splat as a "
       "binned gather) or the paper's rasterised slice march and slice splat; accepted and "
       "reported unused on the CPU"},
      {"evaluator", "string", "volume-tracer", "a registered radiance evaluator",
       "how S and ∇S are computed at the samples; methods with samples"},
      {"integrator", "string", "ray-marcher", "a registered integrator",
       "how the image is marched from the volumes; methods with a radiance volume"},
      {"shadow_map", "object", "see shadowMapKeys()", "",
       "the shadow maps of scene objects: every GPU method's, and light-space-march's on the CPU "
       "(depth compare); accepted and unused by the other CPU methods, which trace shadow rays"},
  };
  return keys;
}

const std::vector<KeyDoc>& shadowMapKeys() {
  static const std::vector<KeyDoc> keys = {
      {"type", "string", "vsm", "vsm, depth",
       "variance shadow maps (the paper's: filtered moments, Chebyshev bound) or a plain depth "
       "compare"},
      {"resolution", "int", "1024", "16…4096",
       "texels per side of each map (spot: one, directional: one, point: six cube faces)"},
      {"bias", "number", "1", "[0, 64]",
       "depth bias in texels: the world size of one texel at the point times this; surface "
       "points also move this far along their normal"},
      {"filter", "int", "3", "odd, 1…31",
       "filter width in texels: VSM box-blurs the moments, depth compare averages filter² "
       "compares (PCF); 1 = none"},
      {"bleed_reduction", "number", "0.2", "[0, 1)",
       "VSM light-bleeding reduction: Chebyshev's p remapped to (p − b)/(1 − b), clamped"},
  };
  return keys;
}

const std::vector<KeyDoc>& lightSpaceMarchKeys() {
  static const std::vector<KeyDoc> keys = {
      {"steps", "int", "128", "1…65536, at least interleave²",
       "N: terms of each view ray's sum, equal steps from the visible surface (or the box's far "
       "side) to the eye"},
      {"interleave", "int", "4", "1…32, at most the image's width and height",
       "M: interleaved sampling in M×M pixel blocks; each pixel evaluates every M²-th term, "
       "then a separable M×M block sum (1: the plain march)"},
      {"light_transmittance", "string", "mean", "mean, traced",
       "the light's transmittance: e^(−σt·D̄·d), D̄ the medium's mean density (Tóth & "
       "Umenhoffer's homogeneous model), or the real density traced with step delta1"},
  };
  return keys;
}

const std::vector<KeyDoc>& radialBlurKeys() {
  static const std::vector<KeyDoc> keys = {
      {"samples", "int", "64", "1…4096", "n: samples per pixel along the screen ray to the light"},
      {"density", "number", "1", "(0, 1]",
       "fraction of the pixel→light segment the n samples span (Mitchell's density)"},
      {"weight", "number", "1", "[0, 1e6]", "scale of every sample"},
      {"decay", "number", "1", "[0, 1]", "sample i is scaled by decay^i"},
      {"exposure", "number", "1", "[0, 1e6]", "scale of the sum"},
      {"downsample", "int", "1", "1, 2, 4", "the pre-pass has 1/downsample of the pixels per side"},
      {"guard_band", "number", "0.5", "[0, 10]",
       "the light's screen position is clamped to this many image sizes beyond each edge"},
  };
  return keys;
}

namespace {

/// render.shadow_map (shadowMapKeys()).
ShadowMapSettings parseShadowMap(Params& p) {
  ShadowMapSettings s;
  s.given = p.has("shadow_map");
  if (!s.given) {
    p.allow("shadow_map");
    return s;
  }
  Params sp = p.child("shadow_map");
  s.type = sp.choice("type", {"vsm", "depth"}, "vsm") == "vsm" ? ShadowMapSettings::Type::Vsm
                                                               : ShadowMapSettings::Type::Depth;
  s.resolution = int(sp.integer("resolution", 1024, Interval::closed(16, 4096)));
  s.bias = sp.real("bias", 1.0, Interval::closed(0, 64));
  s.filter = int(sp.integer("filter", 3, Interval::closed(1, 31)));
  if (s.filter % 2 == 0) sp.fail("filter", "must be odd (a kernel centred on the texel)");
  s.bleedReduction = sp.real("bleed_reduction", 0.2, {0.0, 1.0, false, true});
  sp.finish();
  return s;
}

LightSpaceMarchSettings parseLightSpaceMarch(Params& p) {
  LightSpaceMarchSettings s;
  s.steps = int(p.integer("steps", s.steps, Interval::closed(1, 65536)));
  s.interleave = int(p.integer("interleave", s.interleave, Interval::closed(1, 32)));
  if (s.interleave * s.interleave > s.steps)
    p.fail("interleave", "interleave² = " + std::to_string(s.interleave * s.interleave) +
                             " is more than steps = " + std::to_string(s.steps) +
                             ": some pixels of every block would evaluate no term; raise "
                             "render.steps or lower render.interleave");
  s.light = p.choice("light_transmittance", {"mean", "traced"}, "mean") == "mean"
                ? LightTransmittance::Mean
                : LightTransmittance::Traced;
  return s;
}

RadialBlurSettings parseRadialBlur(Params& p) {
  RadialBlurSettings s;
  s.samples = int(p.integer("samples", s.samples, Interval::closed(1, 4096)));
  s.density = p.real("density", s.density, Interval{0.0, 1.0, true, false});
  s.weight = p.real("weight", s.weight, Interval::closed(0, 1e6));
  s.decay = p.real("decay", s.decay, Interval::closed(0, 1));
  s.exposure = p.real("exposure", s.exposure, Interval::closed(0, 1e6));
  s.downsample = int(p.integer("downsample", s.downsample, Interval::closed(1, 4)));
  if (s.downsample == 3) p.fail("downsample", "is 3; allowed: 1, 2, 4");
  s.guardBand = p.real("guard_band", s.guardBand, Interval::closed(0, 10));
  return s;
}

// Bounds on marching work (kMaxViewSteps, kMaxLightSteps): core/limits.h.

std::string sci(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

void checkWork(Params& p, const Scene& scene, const MethodDesc& d, const PipelineSettings& s) {
  const double diag = glm::length(glm::dvec3(scene.medium.bounds.extent()));
  const Camera& c = scene.camera;
  const double rays = double(c.width) * c.height * c.spp;
  // Methods that do not step by march_step (light-space-march: `steps` per ray, at most 65536)
  // have no view bound here.
  const double perRay = d.viewMarch ? std::ceil(diag / s.march.step) : 0.0;
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
  // The per-pixel competitors step a fixed count per ray: their view work is rays x steps, and
  // each step traces the lights (issue 26: renders of hours or days were accepted).
  const auto checkTerms = [&](const std::string& key, double terms, const std::string& how) {
    if (terms > kMaxViewSteps)
      throw LimitError("'" + p.keyPath(key) + "': " + how + " make " + sci(terms) +
                       " view-ray terms, above the bound of " + sci(kMaxViewSteps) +
                       "; use fewer steps or a smaller image");
  };
  if (d.integrator == "exact") {
    light = view * perLight;
    what = "at every one of " + sci(view) + " view steps";
  } else if (d.reconstruction == "per-voxel") {
    const IVec3 r = s.radianceResolution;
    const double voxels = double(r.x) * r.y * r.z;
    light = voxels * perLight;
    what = "at every one of " + sci(voxels) + " voxels";
  } else if (d.integrator == "jittered-march") {
    const int ds = s.jittered.downsample;
    const double low = std::ceil(double(c.width) / ds) * std::ceil(double(c.height) / ds);
    const double terms = low * s.jittered.steps;
    checkTerms("steps", terms,
               sci(low) + " rays (1/" + std::to_string(ds) + " of " + size + ") x " +
                   std::to_string(s.jittered.steps) + " steps");
    light = terms * perLight;
    what = "at every one of " + sci(terms) + " view steps";
  } else if (d.integrator == "froxel") {
    const IVec3 g = s.froxel.grid;
    const double froxels = double(g.x) * g.y * g.z;
    if (s.froxel.transmittanceMap) {
      const double n = std::pow(double(s.froxel.mapResolution), 3.0);
      light = n * perLight;
      what = "at every one of " + sci(n) + " voxels of the transmittance maps";
    } else {
      light = froxels * perLight;
      what = "at every one of " + sci(froxels) + " froxels";
    }
  } else if (d.integrator == "light-space-march") {
    const LightSpaceMarchSettings& l = s.lightSpaceMarch;
    const double terms =
        rays * std::ceil(double(l.steps) / (double(l.interleave) * double(l.interleave)));
    checkTerms("steps", terms,
               size + " x " + std::to_string(l.steps) + " steps / interleave " +
                   std::to_string(l.interleave) + "^2");
    if (l.light == LightTransmittance::Traced) {
      light = terms * perLight;
      what = "at every one of " + sci(terms) + " view-ray terms (light_transmittance traced)";
    }
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
  if (d.viewMarch) {
    s.march.step = p.real("march_step", voxel, steps);
    s.march.minTransmittance = p.real("min_transmittance", 1e-6, Interval::closed(0, 1));
    s.march.fast = p.boolean("fast_march", true);
    s.march.scale = int(p.integer("march_scale", 1, Interval::closed(1, 4)));
    if (s.march.scale == 3) p.fail("march_scale", "is 3; allowed: 1, 2, 4");
    if (s.march.scale > 1 && scene.camera.spp > 1)
      p.fail("march_scale", "is " + std::to_string(s.march.scale) +
                                "; a reduced march needs camera.spp = 1 (got " +
                                std::to_string(scene.camera.spp) + ")");
    for (const char* k : {"fast_march", "march_scale", "half_float_volumes", "march_simd"})
      if (p.has(k)) s.cpuMarchKeysGiven.push_back(p.keyPath(k));
    if (d.radianceVolume()) {
      s.march.halfFloat = p.boolean("half_float_volumes", false);
      const std::string simd = p.choice("march_simd", {"auto", "sse2", "avx2"}, "auto");
      s.march.simd = simd == "sse2"   ? MarchSimd::Sse2
                     : simd == "avx2" ? MarchSimd::Avx2
                                      : MarchSimd::Auto;
    }
  }
  s.delta1 = p.real("delta1", voxel, steps);
  s.shadowMap = parseShadowMap(p);
  if (d.integrator == "light-space-march") s.lightSpaceMarch = parseLightSpaceMarch(p);
  if (d.integrator == "radial-blur") s.radialBlur = parseRadialBlur(p);
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
    for (const char* k : {"slicing", "gpu_pipeline"})
      if (p.has(k)) s.gpuKeysGiven.push_back(p.keyPath(k));
    s.slicing = p.choice("slicing", {"ray-steps", "view-planes"}, "ray-steps") == "ray-steps"
                    ? Slicing::RaySteps
                    : Slicing::ViewPlanes;
    s.gpuPipeline = p.choice("gpu_pipeline", {"compute", "raster"}, "compute") == "compute"
                        ? GpuPipeline::Compute
                        : GpuPipeline::Raster;
  }
  // The per-pixel competitors' own keys (methods/march_settings.cpp). They march one ray per
  // (low-resolution) pixel or froxel column: no camera.spp.
  if (d.integrator == "jittered-march") s.jittered = parseJitteredMarch(p);
  if (d.integrator == "froxel") s.froxel = parseFroxel(p);
  if ((d.integrator == "jittered-march" || d.integrator == "froxel") && scene.camera.spp > 1)
    throw ConfigError("camera.spp: " + d.name +
                      " renders one ray per pixel; camera.spp must be 1 (got " +
                      std::to_string(scene.camera.spp) + ")");
  checkWork(p, scene, d, s);
  return s;
}

std::vector<std::string> methodKeys(const MethodDesc& d) {
  std::vector<std::string> k = {"delta1", "shadow_map"};
  if (d.viewMarch)
    k.insert(k.end(), {"march_step", "min_transmittance", "fast_march", "march_scale"});
  if (d.integrator == "light-space-march")
    for (const KeyDoc& key : lightSpaceMarchKeys()) k.emplace_back(key.name);
  if (d.integrator == "radial-blur")
    for (const KeyDoc& key : radialBlurKeys()) k.emplace_back(key.name);
  if (d.sampler)
    k.insert(k.end(), {"delta2", "paper", "factor_lights", "log_space", "occlusion_weights",
                       "bounded_taylor", "sampler", "evaluator"});
  if (d.radianceVolume()) k.insert(k.end(), {"radiance_resolution", "slicing", "gpu_pipeline"});
  if (d.radianceVolume() && d.viewMarch) k.insert(k.end(), {"half_float_volumes", "march_simd"});
  if (d.integratorSelectable) k.push_back("integrator");
  if (!d.refiner.empty())
    for (const KeyDoc& key : dynamicSamplingKeys()) k.emplace_back(key.name);
  if (d.integrator == "jittered-march")
    for (const KeyDoc& key : jitteredMarchKeys()) k.emplace_back(key.name);
  if (d.integrator == "froxel")
    for (const KeyDoc& key : froxelKeys()) k.emplace_back(key.name);
  return k;
}

std::unique_ptr<Sampler> makeSampler(Params& p, const Scene& scene, std::string& type,
                                     const std::string& extendedDefault,
                                     long long* plannedSamples) {
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
  if (plannedSamples) {
    // `count` has been validated by the sampler (an integer in [1, 1e8]).
    const long long count = sp.has("count") && sp.raw("count").is_number()
                                ? (long long)sp.raw("count").get<double>()
                                : -1;
    const long long gaussians =
        hasGaussians ? (long long)scene.medium.density->gaussians()->size() : 0;
    *plannedSamples = type == "gaussian-centres"
                          ? (count >= 0 ? std::min(count, gaussians) : gaussians)
                      : count >= 0 ? count
                                   : kDefaultSampleCount;
  }
  return sampler;
}

void checkRenderPlan(Params& p, const Scene& scene, const MethodDesc& d, const PipelineSettings& s,
                     long long samples, bool gradients, const DynamicSamplingSettings* dynamic,
                     bool cpuRayMarcher, bool cpu) {
  const auto voxels = [](IVec3 r) { return double(r.x) * double(r.y) * double(r.z); };
  const auto dims = [](IVec3 r) {
    return std::to_string(r.x) + "x" + std::to_string(r.y) + "x" + std::to_string(r.z);
  };
  const IVec3 res = scene.medium.resolution;
  MemoryPlan plan;
  plan.add("medium.resolution", "the density volume of " + dims(res) + " voxels",
           voxels(res) * sizeof(float));
  const IVec3 blocks = (res + IVec3(7)) / IVec3(8);  // MaxDensityGrid::kBlock
  plan.add("medium.resolution", "the max-density grid", voxels(blocks) * sizeof(float));
  if (const auto* sog = dynamic_cast<const SogDensity*>(scene.medium.density.get()))
    plan.add("medium.file", "the .sog model's residual hash",
             double(sog->model().residual.memoryBytes()));
  if (const auto* g = scene.medium.density ? scene.medium.density->gaussians() : nullptr)
    plan.add("medium", "the medium's " + std::to_string(g->size()) + " Gaussians",
             double(g->size()) * sizeof(GaussianBlob));
  const Camera& c = scene.camera;
  plan.add("camera.width', 'camera.height",
           "an image of " + std::to_string(c.width) + "x" + std::to_string(c.height) + " pixels",
           double(c.width) * double(c.height) * 32.0);
  if (d.radianceVolume()) {
    const IVec3 r = s.radianceResolution;
    plan.add(p.keyPath("radiance_resolution"),
             "the source-radiance volume of " + dims(r) + " voxels", voxels(r) * sizeof(Vec3));
    // The fast march fuses density and radiance (4 floats per voxel) when their grids agree.
    if (d.viewMarch && s.march.fast && cpuRayMarcher && r == res)
      plan.add(p.keyPath("fast_march"),
               "the fused density + radiance volume of " + dims(r) + " voxels",
               voxels(r) * 4 * sizeof(float));
  }
  const double perSample = double(sizeof(RadianceSample));
  if (samples > 0)
    plan.add(p.keyPath("sampler.count"), std::to_string(samples) + " radiance samples",
             double(samples) * (perSample + 2 * sizeof(std::int64_t)));
  // Probes are traced only when there is a level to split into.
  const int probes = dynamic && !dynamic->levels.empty() ? dynamic->probes : 0;
  if (probes > 0 && samples > 0) {
    plan.add(p.keyPath("probes"),
             "the probes of " + std::to_string(samples) + " level-0 samples (" +
                 std::to_string(dynamic->probes) + " each)",
             double(samples) * dynamic->probes * perSample);
    const double n = std::pow(double(dynamic->levels.back()), 3.0);
    plan.add(p.keyPath("levels"),
             "the grid buffer of level " + std::to_string(dynamic->levels.back()) + "^3",
             n * (sizeof(std::uint8_t) + sizeof(std::int32_t)));
  }
  // The competitors' own host arrays (CPU): the froxel volume (in-scattered RGB + transmittance)
  // and the per-light transmittance maps; light-space-march's shadow maps of the scene objects,
  // up to 6 layers (a cube) per point or wide spot light, 1 per directional light.
  if (cpu && d.integrator == "froxel") {
    const IVec3 g = s.froxel.grid;
    plan.add(p.keyPath("froxel_grid"), "the froxel volume of " + dims(g) + " froxels",
             voxels(g) * (sizeof(Vec3) + sizeof(float)));
    if (s.froxel.transmittanceMap)
      plan.add(p.keyPath("transmittance_map_resolution"),
               std::to_string(scene.lights.size()) + " transmittance maps of " +
                   std::to_string(s.froxel.mapResolution) + "^3",
               double(scene.lights.size()) * std::pow(double(s.froxel.mapResolution), 3.0) *
                   sizeof(float));
  }
  if (cpu && d.integrator == "light-space-march" && scene.objects) {
    double layers = 0;
    for (const Light& l : scene.lights) layers += l.type == Light::Type::Directional ? 1 : 6;
    const double r = s.shadowMap.resolution;
    plan.add(p.keyPath("shadow_map.resolution"),
             "the shadow maps (" + sci(layers) + " layers of " + sci(r) + "^2 texels)",
             layers * r * r * sizeof(float));
  }
  plan.check();

  // The samples' tracing: every traced point marches ⌈diagonal / delta1⌉ steps to each light.
  if (samples <= 0) return;
  const double diag = glm::length(glm::dvec3(scene.medium.bounds.extent()));
  const double perTrace =
      std::ceil(diag / s.delta1) * double(std::max<size_t>(1, scene.lights.size()));
  const double points = 1.0 + (gradients || dynamic ? 6.0 : 0.0) + probes;
  const double steps = double(samples) * points * perTrace;
  if (steps > kMaxLightSteps) {
    std::string keys = "'" + p.keyPath("sampler.count") + "', '" + p.keyPath("delta1") + "'";
    if (probes) keys += ", '" + p.keyPath("probes") + "'";
    throw LimitError(keys + ": evaluating " + std::to_string(samples) + " samples traces " +
                     sci(points) + " points each (S" + (points > 1 ? ", 6 for its gradient" : "") +
                     (probes ? ", " + std::to_string(probes) + " probes" : "") + ") with " +
                     sci(perTrace) + " light-march steps each (delta1 " + sci(s.delta1) + "), " +
                     sci(steps) + " steps in all, above the bound of " + sci(kMaxLightSteps) +
                     (probes ? " (level 0 alone; finer levels add more)" : "") +
                     "; use fewer samples or a longer delta1");
  }
}

}  // namespace scatterlab
