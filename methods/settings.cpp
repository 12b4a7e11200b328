#include "methods/settings.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "core/limits.h"
#include "core/work_limits.h"
#include "media/sog.h"
#include "sampling/dynamic_sampling.h"
#include "sampling/samplers.h"

namespace scatterlab {

const std::vector<KeyDoc>& shadowMapKeys() {
  static const std::vector<KeyDoc> keys = {
      {"type", "string", "vsm", "vsm, depth",
       "variance shadow maps (the paper's: filtered moments, Chebyshev bound) or a plain depth "
       "compare",
       R"("depth")"},
      {"resolution", "int", "1024", "16…4096",
       "texels per side of each map (spot: one, directional: one, point: six cube faces)", "64"},
      {"bias", "number", "1", "[0, 64]",
       "depth bias in texels: the world size of one texel at the point times this; surface "
       "points also move this far along their normal",
       "2"},
      {"filter", "int", "3", "odd, 1…31",
       "filter width in texels: VSM box-blurs the moments, depth compare averages filter² "
       "compares (PCF); 1 = none",
       "5"},
      {"bleed_reduction", "number", "0.2", "[0, 1)",
       "VSM light-bleeding reduction: Chebyshev's p remapped to (p − b)/(1 − b), clamped", "0.5"},
  };
  return keys;
}

namespace {

// The pipeline's own keys, in groups read as the method's stages need them (methodKeyTable());
// each stage's keys are in its family's file (StageDecl).

/// Every method's.
const std::vector<KeyDoc>& commonKeys() {
  static const std::vector<KeyDoc> keys = {
      {"delta1", "number", "one voxel edge", "(diag·1e-6, diag]",
       "volume-tracing step towards the lights (the paper's Δ1)", "0.5"},
      {"shadow_map", "object", "see the table below", "",
       "the shadow maps of scene objects: every GPU method's, and light-space-march's on the CPU "
       "(depth compare); accepted and unused by the other CPU methods, which trace shadow rays",
       "", shadowMapKeys},
  };
  return keys;
}

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

void parseCommon(Params& p, const Scene& scene, PipelineSettings& s) {
  s.delta1 = p.real("delta1", scene.medium.voxelSize(),
                    stepRange(glm::length(scene.medium.bounds.extent())));
  s.shadowMap = parseShadowMap(p);
}

/// The view march's (integrators that declare StageDecl::viewMarch).
const std::vector<KeyDoc>& viewMarchKeys() {
  static const std::vector<KeyDoc> keys = {
      {"march_step", "number", "one voxel edge", "(diag·1e-6, diag], diag = box diagonal",
       "view-ray step (world units)", "0.5"},
      {"min_transmittance", "number", "1e-6", "[0, 1]",
       "a view ray stops when its transmittance falls below this", "0.5"},
      {"fast_march", "bool", "true", "true, false",
       "CPU march: skip blocks of zero density, march in tiles, one fused density + radiance "
       "lookup per step; every CPU shadow ray (exact's, the voxels' and the samples') 4 or 8 "
       "steps at once (SIMD), stopped where no light gets through (same images within 1e-6); "
       "false: the plain march and scalar shadow rays (reference)",
       "false", nullptr, "cpu"},
      {"glow", "bool", "true", "true, false",
       "next to a point or spot light the march takes a light's term of A (factored lights) or "
       "of S (exact) as its mean over up to 32 points of the step, resolving the light's glow "
       "(docs/fidelity.md, \"Glows\"); false: at each step's midpoint only (before 2026-11-30)",
       "false"},
      {"march_scale", "int", "1", "1, 2, 4 (2 and 4 need camera.spp = 1)",
       "CPU view march at 1/scale of the resolution per axis (one ray per scale × scale pixels), "
       "upsampled depth-aware to full resolution (box entry/exit depths; edges marched in full); "
       "error in docs/benchmarks.md",
       "2", nullptr, "cpu"},
  };
  return keys;
}

void parseViewMarch(Params& p, const Scene& scene, PipelineSettings& s) {
  s.march.step = p.real("march_step", scene.medium.voxelSize(),
                        stepRange(glm::length(scene.medium.bounds.extent())));
  s.march.minTransmittance = p.real("min_transmittance", 1e-6, Interval::closed(0, 1));
  s.march.fast = p.boolean("fast_march", true);
  s.march.glow = p.boolean("glow", true);
  s.march.scale = int(p.integer("march_scale", 1, Interval::closed(1, 4)));
  if (s.march.scale == 3) p.fail("march_scale", "is 3; allowed: 1, 2, 4");
  if (s.march.scale > 1 && scene.camera.spp > 1)
    p.fail("march_scale", "is " + std::to_string(s.march.scale) +
                              "; a reduced march needs camera.spp = 1 (got " +
                              std::to_string(scene.camera.spp) + ")");
}

/// Methods with samples: what the samples hold, and the stages that make them.
const std::vector<KeyDoc>& sampleKeys() {
  static const std::vector<KeyDoc> keys = {
      {"paper", "bool", "false", "true, false",
       "the paper's algorithm exactly: every extension off; methods with samples", "false"},
      {"factor_lights", "bool", "true for gradient and adaptive, else false (false with paper)",
       "true, false",
       "interpolate S divided by the lights' analytic unshadowed source radiance, multiply it "
       "back at each march step (singular lights); methods with samples",
       "true"},
      {"lamp_model", "bool",
       "true with factor_lights in scenes without objects that have a point or spot light "
       "inside the medium's box; false with paper",
       "true, false (true needs factor_lights)",
       "A also holds each point or spot light's transmittance through a homogeneous medium of "
       "the light's own extinction, saturating at optical depth 2, so V = S / A has no cusp at "
       "lamps inside the medium; methods with samples",
       "false"},
      {"far_field", "number", "0 (off)",
       "0, or 2…1024 (needs factor_lights and an isotropic phase)",
       "A's far field: the factored march evaluates a point light's term of A only within 2 × "
       "this many voxels of it and takes the rest from a grid of the far terms (one vertex per "
       "voxel corner, kept while the lights stay), so a step near no lamp costs one lookup "
       "instead of a term per light; image within 0.005-0.05 % of every light exact at 16 "
       "(docs/gpu.md, \"A's far field on a grid\"). CPU: both marches; GPU: the compute "
       "pipeline",
       "0"},
      {"sampler", "object", "see the table below", "",
       "where the samples are placed (render.sampler); methods with samples", "", samplerKeys},
      {"evaluator", "string", "volume-tracer", "a registered radiance evaluator",
       "how S and ∇S are computed at the samples; methods with samples", R"("volume-tracer")"},
  };
  return keys;
}

/// A number as a message shows it: six significant digits, no trailing zeros (0.2, not
/// 0.200000003).
std::string shortNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

/// paper, factor_lights, lamp_model (sampler and evaluator: planMethod; log_space, which
/// interpolates ln V, is the interpolating reconstructions' key). `extended`: the method's
/// extensions are on by default.
void parseSampleValues(Params& p, const Scene& scene, PipelineSettings& s, bool extended) {
  s.paper = p.boolean("paper", false);
  s.factorLights = p.boolean("factor_lights", extended && !s.paper);
  if (s.paper && s.factorLights)
    p.fail("factor_lights", "is an extension; it cannot be true with render.paper = true");
  // Default chosen by measurement (docs/fidelity.md §8): a clear win with lamps inside smoke
  // and fog, but it loses at the hard shadows of scene objects (window: 6.6 % -> 7.3 %), so it
  // is on only in scenes without objects, and only where a point or spot light lies inside the
  // medium's box (elsewhere it changes nothing but the looser bound of Eq. 5's Taylor clamp).
  const bool lampInside =
      std::any_of(scene.lights.begin(), scene.lights.end(), [&](const Light& l) {
        return l.type != Light::Type::Directional && scene.medium.bounds.contains(l.position);
      });
  s.lampModel = p.boolean("lamp_model", s.factorLights && !s.paper && !scene.objects && lampInside);
  if (s.paper && s.lampModel)
    p.fail("lamp_model", "is an extension; it cannot be true with render.paper = true");
  if (s.lampModel && !s.factorLights)
    p.fail("lamp_model", "is part of factor_lights' A; it needs factor_lights = true");
  s.march.farField = float(p.real("far_field", 0.0, Interval::closed(0, 1024)));
  if (s.march.farField > 0.0f) {
    if (s.paper) p.fail("far_field", "is an extension; it cannot be set with render.paper = true");
    if (!s.factorLights)
      p.fail("far_field", "splits factor_lights' A; it needs factor_lights = true");
    if (s.march.farField < 2.0f)
      p.fail("far_field",
             "is " + shortNumber(s.march.farField) + " voxels; allowed: 0 (off) or 2 to 1024");
    const Phase& ph = scene.medium.phase;
    if (ph.type != Phase::Type::Isotropic && ph.g != 0.0f)
      p.fail("far_field",
             "needs an isotropic phase function (medium.phase has g = " + shortNumber(ph.g) +
                 "): with Henyey-Greenstein A's far part depends on the direction to the camera");
  }
}

/// Methods whose row has a whole-scene fallback (MethodDesc::wholeSceneFallback).
const std::vector<KeyDoc>& wholeSceneFallbackKeys() {
  static const std::vector<KeyDoc> keys = {
      {"voxel_switch", "number", "4 (0 with paper)", "0…1000 (not with paper)",
       "`gradient` and `adaptive`: the whole-scene fallback: where the medium's occupied voxels "
       "(D > 0) that a light reaches — under spot lights only, at most the voxels holding "
       "density in the cells that a cone reaches (stat `lit_voxels`: a bound from the lights and "
       "the occupied voxels per cell of a ≤ 32³ grid, taken once per density) — are at most "
       "`voxel_switch` × the traces of the method's samples (gradient: the planned samples × 7, "
       "S and the six differences of ∇S; adaptive: the initial samples × (1 + `probes`), the "
       "first level's alone), per-voxel traces less than the samples would (a sparse medium: "
       "wisps, small puffs; a narrow shaft through fog; a small volume), and the scene is "
       "rendered as per-voxel renders it, its voxels holding V = S / A with `factor_lights` "
       "(stats `voxels_instead`, `occupied_voxels`); 0: never. Chosen on the population "
       "(docs/fidelity.md, \"The whole-scene fallback\", \"gradient's whole-scene fallback, "
       "built\")",
       "0"},
  };
  return keys;
}

void parseWholeSceneFallback(Params& p, PipelineSettings& s) {
  if (s.paper && p.has("voxel_switch"))
    p.fail("voxel_switch", "is an extension; it cannot be set with render.paper = true");
  s.voxelSwitch =
      p.number("voxel_switch", s.paper ? 0.0 : kVoxelSwitch, Interval::closed(0.0, 1000.0));
}

/// Methods with a source-radiance volume.
const std::vector<KeyDoc>& radianceVolumeKeys() {
  static const std::vector<KeyDoc> keys = {
      {"radiance_resolution", "int or [nx,ny,nz]", "medium.resolution",
       "1…4096 per axis, integers, at most 512³ voxels",
       "voxels of the source-radiance volume; methods that build one", "8"},
      {"gpu_pipeline", "string", "compute", "compute, raster",
       "GPU backend: compute shaders (view march one invocation per pixel, radiance splat as a "
       "binned gather) or the paper's rasterised slice march and slice splat; accepted and "
       "reported unused on the CPU",
       R"("raster")", nullptr, "gpu"},
  };
  return keys;
}

void parseRadianceVolume(Params& p, const Scene& scene, PipelineSettings& s) {
  s.radianceResolution = p.resolution("radiance_resolution", scene.medium.resolution, sizeof(Vec3),
                                      "the source-radiance volume (RGB float)");
  s.radianceReach = glm::length(scene.medium.bounds.extent() / Vec3(s.radianceResolution));
  s.gpuPipeline = p.choice("gpu_pipeline", {"compute", "raster"}, "compute") == "compute"
                      ? GpuPipeline::Compute
                      : GpuPipeline::Raster;
}

/// Methods whose row lets render.integrator replace its integrator.
const std::vector<KeyDoc>& integratorChoiceKeys() {
  static const std::vector<KeyDoc> keys = {
      {"integrator", "string", "ray-marcher", "a registered integrator",
       "how the image is marched from the volumes; methods with a radiance volume",
       R"("ray-marcher")"},
  };
  return keys;
}

/// The declarations of the stages a method runs, in reading order: `evaluator` (with samples),
/// `d`'s reconstruction and refiner, and `integrator`.
std::vector<const StageDecl*> stageDecls(const MethodDesc& d, const std::string& evaluator,
                                         const std::string& integrator,
                                         const std::string& evaluatorKey = "render.evaluator",
                                         const std::string& integratorKey = "render.method") {
  std::vector<const StageDecl*> out;
  if (d.sampler) out.push_back(&radianceEvaluators().get(evaluator, evaluatorKey).decl);
  if (d.radianceVolume())
    out.push_back(&reconstructions().get(d.reconstruction, "render.method").decl);
  if (!d.refiner.empty()) out.push_back(&refiners().get(d.refiner, "render.method").decl);
  out.push_back(&integrators().get(integrator, integratorKey).decl);
  return out;
}

/// The row's default stages.
std::vector<const StageDecl*> stageDecls(const MethodDesc& d) {
  return stageDecls(d, d.evaluator, d.integrator);
}

/// The tables of the keys of `d` running `stages` (stageDecls()), in reading order
/// (methodKeyTable()).
std::vector<const std::vector<KeyDoc>*> keyTables(const MethodDesc& d,
                                                  const std::vector<const StageDecl*>& stages) {
  std::vector<const std::vector<KeyDoc>*> t;
  if (stages.back()->viewMarch) t.push_back(&viewMarchKeys());
  t.push_back(&commonKeys());
  if (d.sampler) t.push_back(&sampleKeys());
  if (d.radianceVolume()) t.push_back(&radianceVolumeKeys());
  if (!d.wholeSceneFallback.empty()) t.push_back(&wholeSceneFallbackKeys());
  if (d.integratorSelectable) t.push_back(&integratorChoiceKeys());
  for (const StageDecl* st : stages)
    for (const KeyGroup& g : st->keys) t.push_back(&g.table());
  return t;
}

// Bounds on marching work (kMaxViewSteps, kMaxLightSteps): core/limits.h.

std::string sci(double v) {
  return formatCount(v);
}

void checkWork(Params& p, const Scene& scene, const std::vector<const StageDecl*>& stages,
               const PipelineSettings& s) {
  const double diag = glm::length(glm::dvec3(scene.medium.bounds.extent()));
  const Camera& c = scene.camera;
  const double rays = double(c.width) * c.height * c.spp;
  // Methods that do not step by march_step (light-space-march: `steps` per ray, at most 65536)
  // have no view bound here.
  const double perRay = stages.back()->viewMarch ? std::ceil(diag / s.march.step) : 0.0;
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
  for (const StageDecl* st : stages) {
    if (st->work) {
      // The competitors: their own steps and the points that trace the lights.
      const StageWork w = st->work(scene, s);
      if (w.viewTerms > kMaxViewSteps)
        throw LimitError("'" + p.keyPath(w.termsKey) + "': " + w.termsHow + " make " +
                         sci(w.viewTerms) + " view-ray terms, above the bound of " +
                         sci(kMaxViewSteps) + "; use fewer steps or a smaller image");
      if (w.lightPoints > 0) {
        light = w.lightPoints * perLight;
        what = w.lightWhat;
      }
    }
    if (st->lightWork == LightWork::EveryViewStep) {
      light = view * perLight;
      what = "at every one of " + sci(view) + " view steps";
    } else if (st->lightWork == LightWork::EveryVoxel) {
      const IVec3 r = s.radianceResolution;
      const double voxels = double(r.x) * r.y * r.z;
      light = voxels * perLight;
      what = "at every one of " + sci(voxels) + " voxels";
    }
  }
  if (light > kMaxLightSteps)
    throw LimitError("'" + p.keyPath("delta1") + "': a step of " + sci(s.delta1) + " gives " +
                     sci(perLight) + " light-march steps " + what + ", " + sci(light) +
                     " in all, above the bound of " + sci(kMaxLightSteps) +
                     "; use a longer step, a smaller image or volume");
}

/// Reads the keys of `d` running `stages` into their settings (parsePipelineSettings).
PipelineSettings parseSettings(Params& p, const Scene& scene, const MethodDesc& d,
                               const std::vector<const StageDecl*>& stages) {
  PipelineSettings s;
  s.refinedSamples = !d.refiner.empty();
  const StageDecl& integrator = *stages.back();
  if (integrator.viewMarch) parseViewMarch(p, scene, s);
  parseCommon(p, scene, s);
  if (d.sampler) parseSampleValues(p, scene, s, d.extended);
  if (d.radianceVolume()) parseRadianceVolume(p, scene, s);
  if (!d.wholeSceneFallback.empty()) parseWholeSceneFallback(p, s);
  for (const StageDecl* st : stages)
    for (const KeyGroup& g : st->keys) g.parse(p, scene, s);
  // The integrators that march one ray per (low-resolution) pixel or froxel column.
  if (integrator.onePerPixel && scene.camera.spp > 1)
    throw ConfigError("camera.spp: " + d.name +
                      " renders one ray per pixel; camera.spp must be 1 (got " +
                      std::to_string(scene.camera.spp) + ")");
  checkWork(p, scene, stages, s);
  return s;
}

}  // namespace

bool voxelsInstead(double voxelSwitch, long long litVoxels, double sampledTraces) {
  return voxelSwitch > 0.0 && sampledTraces > 0.0 &&
         double(litVoxels) <= voxelSwitch * sampledTraces;
}

std::vector<KeyDoc> methodKeyTable(const MethodDesc& d) {
  std::vector<KeyDoc> rows;
  for (const std::vector<KeyDoc>* t : keyTables(d, stageDecls(d)))
    rows.insert(rows.end(), t->begin(), t->end());
  return rows;
}

std::vector<std::string> methodKeys(const MethodDesc& d) {
  std::vector<std::string> k;
  for (const KeyDoc& row : methodKeyTable(d)) k.emplace_back(row.name);
  return k;
}

PipelineSettings parsePipelineSettings(Params& p, const Scene& scene, const MethodDesc& d) {
  return parseSettings(p, scene, d, stageDecls(d));
}

MethodPlan planMethod(const MethodDesc& d, Params& p, const Scene& scene, Backend b) {
  MethodPlan plan;
  plan.desc = d;
  plan.backend = b;
  // The stages first: which keys are read follows from them.
  plan.integrator = d.integratorSelectable ? p.string("integrator", d.integrator) : d.integrator;
  if (d.sampler) plan.evaluator = p.string("evaluator", d.evaluator);
  plan.stages = stageDecls(d, d.sampler ? plan.evaluator : d.evaluator, plan.integrator,
                           p.keyPath("evaluator"),
                           d.integratorSelectable ? p.keyPath("integrator") : p.keyPath("method"));
  plan.integratorDecl = plan.stages.back();
  plan.settings = parseSettings(p, scene, d, plan.stages);
  if (d.sampler) {
    plan.sampler = makeSampler(p, scene, plan.samplerType,
                               plan.settings.paper ? SamplerChoice{} : d.extendedSampler);
    plan.plannedSamples = plan.sampler->plannedCount(scene);
  }
  // The keys that mean something on one backend (or the GPU's raster pipeline) only: the
  // others accept them and report them unused.
  const bool raster = b == Backend::Gpu && plan.settings.gpuPipeline == GpuPipeline::Raster;
  if (raster && plan.settings.march.farField > 0.0f)
    throw ConfigError("'" + p.keyPath("far_field") +
                      "': A's far field is built for the compute pipeline; it cannot be set "
                      "with gpu_pipeline = \"raster\"");
  for (const std::vector<KeyDoc>* table : keyTables(d, plan.stages))
    for (const KeyDoc& row : *table) {
      if (row.only.empty() || !p.has(std::string(row.name))) continue;
      const bool used = row.only == "cpu"   ? b == Backend::Cpu
                        : row.only == "gpu" ? b == Backend::Gpu
                                            : raster;  // "gpu-raster"
      if (!used) plan.unusedKeys.push_back(p.keyPath(std::string(row.name)));
    }
  return plan;
}

std::unique_ptr<Sampler> makeSampler(Params& p, const Scene& scene, std::string& type,
                                     const SamplerChoice& extendedDefault) {
  const bool hasGaussians = scene.medium.density && scene.medium.density->gaussians();
  Json extended = {{"type", extendedDefault.type}, {"count", extendedDefault.count}};
  if (extendedDefault.atMost) extended["at_most"] = true;
  const Json defaultSampler = !extendedDefault.type.empty() ? extended
                              : hasGaussians                ? Json{{"type", "gaussian-centres"}}
                                                            : Json{{"type", "jittered"}};
  const bool given = p.has("sampler");
  Params sp = given ? p.child("sampler") : Params(defaultSampler, p.keyPath("sampler"));
  if (!given) p.allow("sampler");
  type = sp.string("type", defaultSampler["type"].get<std::string>());
  std::unique_ptr<Sampler> sampler = samplers().get(type, sp.keyPath("type"))(sp, scene);
  sp.finish();
  return sampler;
}

void checkRenderPlan(Params& p, const Scene& scene, const MethodPlan& plan, bool gradients) {
  const MethodDesc& d = plan.desc;
  const PipelineSettings& s = plan.settings;
  const long long samples = plan.plannedSamples;
  const bool cpu = plan.backend == Backend::Cpu;
  // What the stages declare beyond the pipeline's own volumes (StageDecl::work).
  std::vector<StageWork> works;
  for (const StageDecl* st : plan.stages)
    if (st->work) works.push_back(st->work(scene, s));
  const auto voxels = [](IVec3 r) { return double(r.x) * double(r.y) * double(r.z); };
  const auto dims = [](IVec3 r) {
    return std::to_string(r.x) + "x" + std::to_string(r.y) + "x" + std::to_string(r.z);
  };
  const IVec3 res = scene.medium.resolution;
  MemoryPlan memory;
  memory.add("medium.resolution", "the density volume of " + dims(res) + " voxels",
             voxels(res) * sizeof(float));
  const IVec3 blocks = (res + IVec3(7)) / IVec3(8);  // MaxDensityGrid::kBlock
  memory.add("medium.resolution", "the max-density grid", voxels(blocks) * sizeof(float));
  if (const auto* sog = dynamic_cast<const SogDensity*>(scene.medium.density.get()))
    memory.add("medium.file", "the .sog model's residual hash",
               double(sog->model().residual.memoryBytes()));
  if (const auto* g = scene.medium.density ? scene.medium.density->gaussians() : nullptr)
    memory.add("medium", "the medium's " + std::to_string(g->size()) + " Gaussians",
               double(g->size()) * sizeof(GaussianBlob));
  const Camera& c = scene.camera;
  memory.add(std::vector<std::string>{"camera.width", "camera.height"},
             "an image of " + std::to_string(c.width) + "x" + std::to_string(c.height) + " pixels",
             double(c.width) * double(c.height) * 32.0);
  if (d.radianceVolume()) {
    const IVec3 r = s.radianceResolution;
    memory.add(p.keyPath("radiance_resolution"),
               "the source-radiance volume of " + dims(r) + " voxels", voxels(r) * sizeof(Vec3));
    // The fast march fuses density and radiance (4 floats per voxel) when their grids agree;
    // with A's far field its grid is held as well (a vertex per voxel corner: RGB on the CPU,
    // a vec4 on the GPU).
    const bool far = s.factorLights && s.march.farField > 0.0f;
    if (plan.integratorDecl->viewMarch && plan.integratorDecl->fusedVolumeOnCpu && cpu &&
        s.march.fast && r == res)
      memory.add(p.keyPath("fast_march"),
                 "the fused density + radiance volume of " + dims(r) + " voxels",
                 voxels(r) * 4 * sizeof(float));
    if (far && plan.integratorDecl->viewMarch) {
      // On the GPU with the lights' masks per brick of kFarBrick³ cells (far_mask.comp.glsl): a bit
      // per light and brick.
      const IVec3 v = res + IVec3(1), bricks = (res + IVec3(kFarBrick - 1)) / kFarBrick;
      const double masks =
          cpu ? 0.0 : voxels(bricks) * 4.0 * double((scene.lights.size() + 31) / 32);
      memory.add(p.keyPath("far_field"), "A's far field of " + dims(v) + " vertices",
                 voxels(v) * (cpu ? sizeof(Vec3) : 4 * sizeof(float)) + masks);
    }
  }
  if (samples > 0)
    memory.add(p.keyPath("sampler.count"), std::to_string(samples) + " radiance samples",
               sampleSetBytes(double(samples)));
  // A refiner's probes of the first level, each kept as a sample while it runs; its arrays.
  int probes = 0;
  std::string probesKey;
  bool traced = gradients;
  for (StageWork& w : works) {
    traced = traced || w.tracesGradients;
    if (w.probesPerSample > 0 && samples > 0) {
      probes += w.probesPerSample;
      probesKey = w.probesKey;
      memory.add(p.keyPath(w.probesKey),
                 "the probes of " + std::to_string(samples) + " level-0 samples (" +
                     std::to_string(w.probesPerSample) + " each)",
                 double(samples) * w.probesPerSample * double(sizeof(RadianceSample)));
    }
    if (samples > 0)
      for (MemoryPlan::Item& item : w.arrays) {
        for (std::string& k : item.keys) k = p.keyPath(k);
        memory.add(std::move(item.keys), item.what, item.bytes);
      }
    // The competitors' own host arrays (CPU variants): froxel volumes, transmittance maps,
    // light-space-march's shadow maps.
    if (cpu)
      for (MemoryPlan::Item& item : w.cpuArrays) {
        for (std::string& k : item.keys) k = p.keyPath(k);
        memory.add(std::move(item.keys), item.what, item.bytes);
      }
  }
  memory.check();

  // The samples' tracing: every traced point marches ⌈diagonal / delta1⌉ steps to each light.
  if (samples <= 0) return;
  const double diag = glm::length(glm::dvec3(scene.medium.bounds.extent()));
  const double perTrace =
      std::ceil(diag / s.delta1) * double(std::max<size_t>(1, scene.lights.size()));
  const double points = (traced ? kGradientSampleTraces : 1.0) + probes;
  const double steps = double(samples) * points * perTrace;
  if (steps > kMaxLightSteps) {
    std::string keys = "'" + p.keyPath("sampler.count") + "', '" + p.keyPath("delta1") + "'";
    if (probes) keys += ", '" + p.keyPath(probesKey) + "'";
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
