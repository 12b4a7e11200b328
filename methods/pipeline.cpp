#include "methods/pipeline.h"

#include <array>
#include <optional>

#include "core/error.h"
#include "shading/transport.h"

namespace scatterlab {

namespace {

/// The variant of `name` in `registry` for `b`; a ConfigError naming `key` when the name is
/// unknown or has no variant there.
template <class Maker>
const Maker& variant(const StageRegistry<Maker>& registry, const std::string& name, Backend b,
                     const std::string& key, const std::string& what) {
  const auto& entry = registry.get(name, key);
  if (!entry.has(b)) {
    std::string others;  // the backends that have one
    for (int o = 0; o < kBackendCount; ++o)
      if (o != int(b) && entry.has(Backend(o)))
        others += (others.empty() ? "" : " or ") + std::string(backendName(Backend(o)));
    throw ConfigError("'" + key + "': " + what + " '" + name + "' has no " + backendName(b) +
                      " variant" + (others.empty() ? "" : "; use --backend " + others));
  }
  return entry.on[int(b)];
}

/// One stage of a render: a progress phase, and a wall time that ends when the backend's work
/// is done.
template <class Body>
void runStage(const char* name, Frame& frame, RenderStats& st, Progress* progress,
              const Body& body) {
  if (progress) progress->restart(name, 1);
  ScopedTimer t(st, name);
  body();
  frame.sync();
}

/// What the radiance volume of a render depends on besides the density and the method's keys:
/// the lights, the phase function, σt, the objects (visibility), and the camera position where
/// the source radiance is evaluated towards it (an anisotropic phase function) or dynamic
/// sampling weighs its error by the transmittance to it.
struct RadianceInputs {
  std::vector<Light> lights;
  Phase phase;
  float sigmaT = 0.0f;
  std::shared_ptr<const SceneObjects> objects;
  Vec3 eye{0.0f};
  bool eyeMatters = true;

  RadianceInputs() = default;
  RadianceInputs(const Scene& s, bool refines)
      : lights(s.lights),
        phase(s.medium.phase),
        sigmaT(s.medium.sigmaT),
        objects(s.objects),
        eye(s.camera.position),
        eyeMatters(refines || s.medium.phase.type != Phase::Type::Isotropic) {}

  bool operator==(const RadianceInputs& o) const {
    const auto same = [](const Light& a, const Light& b) {
      return a.type == b.type && a.position == b.position && a.direction == b.direction &&
             a.intensity == b.intensity && a.cosInner == b.cosInner && a.cosOuter == b.cosOuter;
    };
    if (lights.size() != o.lights.size()) return false;
    for (std::size_t i = 0; i < lights.size(); ++i)
      if (!same(lights[i], o.lights[i])) return false;
    return phase.type == o.phase.type && phase.g == o.phase.g && sigmaT == o.sigmaT &&
           objects == o.objects && eyeMatters == o.eyeMatters && (!eyeMatters || eye == o.eye);
  }
};

class PipelineMethod : public Method {
 public:
  PipelineMethod(MethodPlan plan, std::string note)
      : plan_(std::move(plan)),
        desc_(plan_.desc),
        backend_(plan_.backend),
        settings_(plan_.settings),
        note_(std::move(note)) {}

  const MethodPlan& plan() const { return plan_; }

  std::unique_ptr<RadianceEvaluator> evaluator;
  std::unique_ptr<SampleRefiner> refiner;
  std::unique_ptr<Reconstruction> reconstruction;
  /// The row's whole-scene fallback (MethodDesc::wholeSceneFallback: per-voxel's
  /// reconstruction, of what this pipeline's volume holds, V = S / A with factor_lights), for a
  /// medium whose samples would trace more than it (voxelsInstead()).
  std::unique_ptr<Reconstruction> voxelReconstruction;
  std::unique_ptr<Integrator> integrator;

  RenderResult render(const Scene& scene, Progress* progress) override {
    RenderResult r;
    RenderStats& st = r.stats;
    st.method = desc_.name;
    st.backend = backendName(backend_);
    st.width = scene.camera.width;
    st.height = scene.camera.height;
    // The density stage is skipped when the kept frame was built from this very medium.
    const bool reuse = retainDensity && frame_ && kept_.density == scene.medium.density &&
                       kept_.bounds.min == scene.medium.bounds.min &&
                       kept_.bounds.max == scene.medium.bounds.max &&
                       kept_.resolution == scene.medium.resolution;
    std::unique_ptr<Frame> frame =
        reuse ? std::move(frame_) : backends()[int(backend_)].makeFrame(settings_);
    if (reuse) frame->newRender();
    frame->keepImageOnDevice(imageOnDevice && retainDensity);
    const bool radianceKept = keptRadiance_;
    keptRadiance_ = false;  // the frame is taken; set again when this render completes
    const auto stage = [&](const char* name, const auto& body) {
      runStage(name, *frame, st, progress, body);
    };
    if (!reuse) stage("density", [&] { frame->buildDensity(scene); });
    if (retainDensity) st.extra["density_reused"] = reuse;
    // A kept frame whose radiance volume was made from the same inputs marches it again:
    // a camera move with an isotropic phase function, or a change of background or image
    // size, costs only the march.
    const RadianceInputs inputs(scene, bool(refiner));
    const bool reuseRadiance = reuse && reconstruction && radianceKept && keptInputs_ == inputs;
    if (retainDensity && reconstruction) st.extra["radiance_reused"] = reuseRadiance;
    if (reuseRadiance) {
      finish(std::move(frame), scene, r, *keptRadianceSamples_, progress);
      return r;
    }
    // The whole-scene fallback: a medium so sparse that per-voxel traces less than the
    // samples would is rendered as per-voxel renders it. Per-voxel traces the
    // occupied voxels that some light reaches: where only spot lights shine, at most those of
    // the occupied voxels of the cells of a coarse grid that a cone reaches
    // (LitReach::voxelBound). The count and the cells' counts are taken once per density (on a
    // GPU a pass and a small read each); the cones are host geometry, so the decision follows
    // the lights from frame to frame with no wait.
    // Off (voxel_switch 0, render.paper): nothing counted, no pass, no read.
    if (voxelReconstruction && settings_.voxelSwitch <= 0.0) st.extra["voxels_instead"] = false;
    if (voxelReconstruction && settings_.voxelSwitch > 0.0) {
      const IVec3 res = scene.medium.resolution;
      const IVec3 cells = LitReach::boundCells(res);
      if (!reuse || !keptOccupied_) {
        keptOccupied_ = frame->countOccupiedCells(std::span(&res, 1))[0];
        keptOccupiedCells_.clear();
      }
      const LitReach lit(scene.lights);
      long long traced = *keptOccupied_;
      st.extra["occupied_voxels"] = traced;
      if (!lit.everywhere()) {
        if (keptOccupiedCells_.empty())  // read once per density, when spots alone shine
          keptOccupiedCells_ = frame->occupiedVoxelsPerCell(cells);
        const long long bound = lit.voxelBound(scene.medium.bounds, res, &keptOccupiedCells_);
        st.extra["lit_voxels"] = bound;
        traced = std::min(traced, bound);
      }
      // The sampled path's traces: a refiner's first level (SampleRefiner::tracesPerSample),
      // else S and, for a reconstruction that reads it, the six differences of ∇S.
      const double perSample = refiner                            ? refiner->tracesPerSample()
                               : reconstruction->needsGradients() ? kGradientSampleTraces
                                                                  : 1.0;
      const bool instead = scatterlab::voxelsInstead(settings_.voxelSwitch, traced,
                                                     double(plan_.plannedSamples) * perSample);
      if (refiner) {
        // Per-voxel's traces, in radiance voxels: the unit of dynamic sampling's cost budget.
        const IVec3 rv = settings_.radianceResolution.x > 0 ? settings_.radianceResolution : res;
        const double scale = (double(rv.x) * rv.y * rv.z) / (double(res.x) * res.y * res.z);
        refiner->setPerVoxelTraces(std::max(1LL, (long long)std::llround(double(traced) * scale)));
      }
      st.extra["voxels_instead"] = instead;
      if (instead) {
        samplesOnDevice_ = false;
        ReconstructionStats rs;
        stage("radiance", [&] {
          rs = voxelReconstruction->reconstruct(*frame, scene, {}, settings_.radianceResolution,
                                                progress);
        });
        st.extra["traced_voxels"] = rs.traced;
        st.extra["empty_voxels"] = rs.skipped;
        finish(std::move(frame), scene, r, {}, progress);
        return r;
      }
    }
    // A sampler reads only the medium and its density volume (Sampler), so with the density
    // kept its samples are kept too; S and ∇S are evaluated anew (they depend on the lights).
    std::vector<RadianceSample> samples;
    Sampler* sampler = plan_.sampler.get();
    if (sampler && reuse && keptSamples_) {
      samples = *keptSamples_;
      st.extra["samples_reused"] = true;
    } else if (sampler) {
      stage("sampling", [&] { samples = sampler->generate(*frame, scene); });
      if (retainDensity) {
        keptSamples_ = samples;
        st.extra["samples_reused"] = false;
      }
    }
    if (refiner) {
      DynamicSamplingResult ds;
      stage("dynamic_sampling",
            [&] { ds = refiner->refine(*frame, scene, std::move(samples), *evaluator); });
      // A resident GPU pass (ds.onDevice) reports its levels and count after the frame.
      samplesOnDevice_ = ds.onDevice;
      if (!ds.onDevice) refiner->describe(st, ds);
      samples = std::move(ds.samples);
    } else if (sampler) {
      stage("evaluation",
            [&] { evaluator->evaluate(*frame, scene, samples, reconstruction->needsGradients()); });
    }
    if (reconstruction) {
      const bool fromSamples = reconstruction->usesSamples();
      ReconstructionStats rs;
      stage(fromSamples ? "reconstruction" : "radiance", [&] {
        rs = reconstruction->reconstruct(*frame, scene, samples, settings_.radianceResolution,
                                         progress);
      });
      if (fromSamples) {
        st.extra["uncovered_voxels"] = rs.uncovered;
      } else {
        st.extra["traced_voxels"] = rs.traced;
        st.extra["empty_voxels"] = rs.skipped;
      }
    }
    finish(std::move(frame), scene, r, std::move(samples), progress);
    return r;
  }

 private:
  /// The march and everything after it: the stats, the exports, and keeping the frame.
  void finish(std::unique_ptr<Frame> frame, const Scene& scene, RenderResult& r,
              std::vector<RadianceSample> samples, Progress* progress) {
    RenderStats& st = r.stats;
    runStage("march", *frame, st, progress,
             [&] { r.image = integrator->integrate(*frame, scene, progress); });
    // The last guard of docs/reliability.md: whatever the parse-time bounds miss (products of
    // large but allowed values: intensity, sigma_t, densities, weights), no image with a
    // non-finite pixel leaves a method. (An image left on the GPU, Method::imageOnDevice, is
    // not read back to be checked.)
    if (const NonFiniteValues bad = countNonFinite(r.image); bad.any())
      throw LimitError("method '" + desc_.name + "' (" + backendName(backend_) + ") produced " +
                       bad.describe() +
                       ": the scene's values overflow single precision (3.4e38) somewhere; lower "
                       "the largest of them (light intensity, sigma_t, density, weights); no "
                       "image was written");
    if (reconstruction) {
      const IVec3 res = settings_.radianceResolution;
      st.extra["radiance_resolution"] = {res.x, res.y, res.z};
    }

    frame->report(st);
    integrator->describe(st);
    // The keys the scene set that mean nothing on this backend (MethodPlan::unusedKeys).
    if (!plan_.unusedKeys.empty()) st.extra["unused_keys"] = plan_.unusedKeys;
    if (plan_.sampler) {
      if (!samplesOnDevice_)
        st.samples = (long long)samples.size();
      else if (!st.samples && deviceSampleCount_ >= 0)
        st.samples = deviceSampleCount_;  // the radiance reused: the count of the render it is from
      if (samplesOnDevice_ && st.samples) deviceSampleCount_ = *st.samples;
      st.extra["sampler"] = plan_.samplerType;
      // The extensions as resolved for this scene (their defaults depend on it).
      st.extra["factor_lights"] = settings_.factorLights;
      st.extra["lamp_model"] = settings_.lampModel;
      st.extra["log_space"] = settings_.logSpace;
    }
    if (plan_.integratorDecl->viewMarch) st.extra["march_step"] = settings_.march.step;
    st.extra["delta1"] = settings_.delta1;
    if (!note_.empty()) st.extra["backend_choice"] = note_;
    if (!ignoredKeys.empty()) st.extra["ignored_keys"] = ignoredKeys;
    r.density = frame->exportDensity();
    r.radiance = frame->exportRadiance();
    if (const auto d = frame->deviceImage())
      r.deviceImage = RenderResult::DeviceImage{(*d)[0], int((*d)[1]), int((*d)[2])};
    if (retainDensity) {
      kept_ = scene.medium;
      frame_ = std::move(frame);
      if (reconstruction) {
        keptInputs_ = RadianceInputs(scene, bool(refiner));
        keptRadianceSamples_ = samples;
        keptRadiance_ = true;
      }
    }
    r.samples = std::move(samples);
  }

  std::unique_ptr<Frame> frame_;  ///< kept between renders when retainDensity
  /// The kept density's occupied voxels (Frame::countOccupiedCells), which the whole-scene
  /// fallback's decision starts from.
  std::optional<long long> keptOccupied_;
  /// Per cell of a LitReach::boundCells grid, its voxels that hold density (for the cones'
  /// bound; empty until a frame lit by spots alone needs it).
  std::vector<int> keptOccupiedCells_;
  /// The refiner left the final samples on the device (RenderResult::samples is empty; the
  /// backend's report counts them).
  bool samplesOnDevice_ = false;
  long long deviceSampleCount_ = -1;  ///< their count, as the report of their render read it
  /// The sampler's output for frame_'s density (positions, radii, weights; S and ∇S zero).
  std::optional<std::vector<RadianceSample>> keptSamples_;
  Medium kept_;  ///< the medium frame_'s density was built from
  /// frame_'s radiance volume, the inputs it was made from and the samples it was made of.
  bool keptRadiance_ = false;
  RadianceInputs keptInputs_;
  std::optional<std::vector<RadianceSample>> keptRadianceSamples_;
  MethodPlan plan_;
  const MethodDesc& desc_;
  const Backend backend_;
  const PipelineSettings& settings_;
  std::string note_;
};

}  // namespace

bool pipelineRunsOn(const MethodDesc& d, Backend b) {
  if (!backends()[int(b)].makeFrame) return false;
  const auto has = [b](const auto& registry, const std::string& name) {
    return registry.contains(name) && registry.get(name, name).has(b);
  };
  if (d.sampler && !has(radianceEvaluators(), d.evaluator)) return false;
  if (!d.refiner.empty() && !has(refiners(), d.refiner)) return false;
  if (d.radianceVolume() && !has(reconstructions(), d.reconstruction)) return false;
  if (!d.wholeSceneFallback.empty() && !has(reconstructions(), d.wholeSceneFallback)) return false;
  return has(integrators(), d.integrator);
}

std::unique_ptr<Method> makePipelineMethod(const MethodDesc& d, Params& p, const Scene& scene,
                                           Backend b, std::string note) {
  // Every key is read before any backend-specific choice, so a scene valid on one backend is
  // valid on the other.
  auto m = std::make_unique<PipelineMethod>(planMethod(d, p, scene, b), std::move(note));
  const MethodPlan& pl = m->plan();
  const PipelineSettings& settings = pl.settings;
  if (d.sampler)
    m->evaluator = variant(radianceEvaluators(), pl.evaluator, b, p.keyPath("evaluator"),
                           "radiance evaluator")(settings);
  if (!d.refiner.empty())
    m->refiner = variant(refiners(), d.refiner, b, p.keyPath("method"), "sample refiner")(settings);
  if (!d.wholeSceneFallback.empty())
    m->voxelReconstruction = variant(reconstructions(), d.wholeSceneFallback, b,
                                     p.keyPath("method"), "reconstruction")(settings);
  if (d.radianceVolume())
    m->reconstruction = variant(reconstructions(), d.reconstruction, b, p.keyPath("method"),
                                "reconstruction")(settings);
  m->integrator =
      variant(integrators(), pl.integrator, b, p.keyPath("integrator"), "integrator")(settings);
  // The sum of the planned allocations and the samples' tracing work, before anything is built.
  checkRenderPlan(p, scene, pl, m->reconstruction && m->reconstruction->needsGradients());
  return m;
}

}  // namespace scatterlab
