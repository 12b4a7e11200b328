#include "render/integrators.h"

#include <xsimd/xsimd.hpp>

#include "core/stages.h"
#include "core/transport.h"
#include "render/light_space_march.h"
#include "render/radial_blur.h"
#include "render/froxel.h"
#include "render/jittered_march.h"
#include "render/ray_marcher.h"
#include "render/shadow_rays.h"

namespace scatterlab {

namespace {

/// Density and source radiance interleaved per voxel (D, S.r, S.g, S.b): one trilinear lookup
/// of 4-float batches (xsimd) gives both, with the weights and corner addresses computed once.
/// Built per frame by the fast march when the two volumes share bounds and dimensions.
class DensityRadianceVolume {
 public:
  using Batch = xsimd::make_sized_batch_t<float, 4>;

  DensityRadianceVolume(const DensityGrid& d, const RadianceGrid& r)
      : maxIndex_(d.dims() - 1), maxBase_(glm::max(d.dims() - 2, IVec3(0))) {
    const IVec3 n = d.dims();
    step_ = IVec3(n.x > 1 ? 4 : 0, n.y > 1 ? 4 * n.x : 0, n.z > 1 ? 4 * n.x * n.y : 0);
    rowStride_ = std::size_t(n.x);
    sliceStride_ = std::size_t(n.x) * n.y;
    data_.resize(4 * d.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, d.size(), 1 << 14),
                      [&](const tbb::blocked_range<std::size_t>& b) {
                        for (std::size_t i = b.begin(); i < b.end(); ++i) {
                          const Vec3& s = r.data()[i];
                          float* p = &data_[4 * i];
                          p[0] = d.data()[i];
                          p[1] = s.r;
                          p[2] = s.g;
                          p[3] = s.b;
                        }
                      });
  }
  static bool compatible(const DensityGrid& d, const RadianceGrid& r) {
    return d.dims() == r.dims() && d.bounds().min == r.bounds().min &&
           d.bounds().max == r.bounds().max;
  }

  /// (D, S) at index coordinates u, clamped as Grid3::sampleIndex.
  Batch sample(Vec3 u) const {
    for (int a = 0; a < 3; ++a) {
      u[a] = u[a] > 0.0f ? u[a] : 0.0f;
      u[a] = u[a] < maxIndex_[a] ? u[a] : maxIndex_[a];
    }
    const IVec3 b = glm::min(IVec3(u), maxBase_);
    const Vec3 f = u - Vec3(b);
    const float* p = data_.data() +
                     4 * ((std::size_t(b.z) * sliceStride_) + std::size_t(b.y) * rowStride_ + b.x);
    const std::size_t dx = step_.x, dy = step_.y, dz = step_.z;
    const auto at = [&](std::size_t o) { return Batch::load_aligned(p + o); };
    const Batch fx(f.x), fy(f.y), fz(f.z);
    const auto lerp = [](const Batch& a, const Batch& c, const Batch& t) {
      return a + (c - a) * t;
    };
    const Batch c00 = lerp(at(0), at(dx), fx), c10 = lerp(at(dy), at(dy + dx), fx);
    const Batch c01 = lerp(at(dz), at(dz + dx), fx), c11 = lerp(at(dz + dy), at(dz + dy + dx), fx);
    return lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz);
  }

 private:
  std::vector<float, xsimd::aligned_allocator<float, 16>> data_;
  Vec3 maxIndex_;
  IVec3 maxBase_, step_{0};
  std::size_t rowStride_ = 0, sliceStride_ = 0;
};

/// The march's lookup (DensitySourceLookup's interface) through a DensityRadianceVolume, times
/// the analytic factor A of the lights when the volume holds V = S / A.
struct FusedLookup {
  const DensityRadianceVolume& volume;
  const LightFactor* factor;
  bool operator()(const Vec3& u, const Ray& r, float t, float& D, Vec3& S) const {
    alignas(16) float v[4];
    volume.sample(u).store_aligned(v);
    D = v[0];
    if (D <= 0.0f) return false;
    S = Vec3(v[1], v[2], v[3]);
    if (factor) S *= (*factor)(r.at(t), -r.dir);
    return true;
  }
};

class RayMarcher : public Integrator {
 public:
  explicit RayMarcher(const PipelineSettings& s)
      : march_(s.march),
        slicingGiven_(s.slicingGiven),
        factored_(s.factorLights),
        delta1_(s.delta1) {}
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override {
    const HostFrame& f = static_cast<const HostFrame&>(frame);
    const RadianceGrid& radiance = *f.radiance;
    if (progress) progress->restart("march", scene.camera.height);
    // The volume holds V = S / A; A is analytic (one evaluation per light and step).
    const LightFactor A(scene);
    if (march_.fast && DensityRadianceVolume::compatible(*f.density, radiance)) {
      const DensityRadianceVolume volume(*f.density, radiance);
      return marchWith(scene, *f.density, FusedLookup{volume, factored_ ? &A : nullptr}, march_,
                       progress, delta1_);
    }
    const Vec3 s = radiance.indexScale(), o = radiance.indexOffset();
    if (factored_) {
      const auto lookup = [&](const Vec3& x, const Vec3& toViewer) {
        return radiance.sampleIndex(x * s + o) * A(x, toViewer);
      };
      return marchImage(scene, *f.density, lookup, march_, progress, delta1_);
    }
    const auto lookup = [&](const Vec3& x, const Vec3&) { return radiance.sampleIndex(x * s + o); };
    return marchImage(scene, *f.density, lookup, march_, progress, delta1_);
  }
  void describe(RenderStats& stats) const override {
    // The CPU marcher steps along each ray: a slicing the scene asks for has no meaning here.
    if (slicingGiven_) stats.extra["unused_keys"] = {"render.slicing"};
  }

 private:
  MarchSettings march_;
  bool slicingGiven_;
  bool factored_;
  float delta1_;
};

class ExactIntegrator : public Integrator {
 public:
  explicit ExactIntegrator(const PipelineSettings& s) : march_(s.march), delta1_(s.delta1) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override {
    const DensityGrid& density = frame.hostDensity();
    if (progress) progress->restart("exact", scene.camera.height);
    // The shadow rays stop at an optical depth where no light gets through. (Skipping empty
    // blocks along them too, SourceRadiance's `skip`, was measured slower on smoke1: their
    // steps of three voxels cross a block in about three lookups, and few blocks are empty.)
    // With the fast march the shadow rays are traced with SIMD over their steps
    // (render/shadow_rays.h); the plain march keeps the scalar opticalDepth.
    const SimdShadowRays shadows(density);
    const SourceRadiance source(scene, density, delta1_, nullptr, march_.fast,
                                march_.fast ? shadows.fn() : ShadowDepthFn{});
    return marchImage(scene, density, source, march_, progress, delta1_);
  }

 private:
  MarchSettings march_;
  float delta1_;
};

/// `jittered-march` (render/jittered_march.h): no radiance volume, S traced per sample.
class JitteredMarchIntegrator : public Integrator {
 public:
  explicit JitteredMarchIntegrator(const PipelineSettings& s)
      : s_(s.jittered), march_(s.march), delta1_(s.delta1) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override {
    return jitteredMarch(scene, frame.hostDensity(), s_, march_, delta1_, progress);
  }
  void describe(RenderStats& stats) const override { describeJitteredMarch(stats, s_); }

 private:
  JitteredMarchSettings s_;
  MarchSettings march_;
  float delta1_;
};

/// `froxel` (render/froxel.h).
class FroxelIntegrator : public Integrator {
 public:
  explicit FroxelIntegrator(const PipelineSettings& s)
      : s_(s.froxel), minT_(s.march.minTransmittance), delta1_(s.delta1) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override {
    passes_ = Json::object();
    return froxelRender(scene, frame.hostDensity(), s_, delta1_, minT_, progress, &passes_);
  }
  void describe(RenderStats& stats) const override {
    describeFroxel(stats, s_);
    stats.extra["pass_ms"] = passes_;
  }

 private:
  FroxelSettings s_;
  float minT_, delta1_;
  Json passes_;
};

}  // namespace

void registerIntegrators() {
  integrators().addVariant("jittered-march", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new JitteredMarchIntegrator(s));
  });
  integrators().addVariant("froxel", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new FroxelIntegrator(s));
  });
  integrators().addVariant("ray-marcher", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new RayMarcher(s));
  });
  integrators().addVariant("exact", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new ExactIntegrator(s));
  });
  registerLightSpaceMarch();
  registerRadialBlur();
}

}  // namespace scatterlab
