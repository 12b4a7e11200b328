/// The CPU reference methods: `exact` (per-pixel march, transmittance to each light traced at
/// every step) and `per-voxel` (S traced at every voxel, then marched with trilinear lookups).

#include "render/methods.h"

#include "core/error.h"
#include "core/method.h"
#include "render/per_voxel.h"
#include "render/ray_marcher.h"
#include "render/volume_tracer.h"

namespace scatterlab {

MarchParams parseMarchParams(Params& p, const Scene& scene) {
  MarchParams mp;
  const float voxel = scene.medium.voxelSize();
  const float ext = glm::length(scene.medium.bounds.extent());
  // Refuse steps so small that one ray would take more than ~10^6 steps.
  const Interval range{ext * 1e-6, ext, true, false};
  mp.march.step = p.real("march_step", voxel, range);
  mp.delta1 = p.real("delta1", voxel, range);
  mp.march.minTransmittance = p.real("min_transmittance", 1e-6, Interval::closed(0, 1));
  return mp;
}

DensityGrid buildDensityVolume(const Scene& scene, RenderStats& stats) {
  ScopedTimer t(stats, "density");
  DensityGrid g(scene.medium.bounds, scene.medium.resolution);
  scene.medium.density->build(g);
  return g;
}

Image marchRadianceVolume(const Scene& scene, const DensityGrid& density,
                          const RadianceGrid& radiance, const MarchSettings& march,
                          RenderStats& stats, Progress* progress) {
  ScopedTimer t(stats, "march");
  if (progress) progress->restart("march", scene.camera.height);
  const Vec3 s = radiance.indexScale(), o = radiance.indexOffset();
  const auto lookup = [&](const Vec3& x, const Vec3&) { return radiance.sampleIndex(x * s + o); };
  return marchImage(scene, density, lookup, march, progress);
}

void fillCpuStats(RenderStats& st, const std::string& method, const Scene& scene) {
  st.method = method;
  st.backend = "cpu";
  st.device = "CPU (TBB)";
  st.width = scene.camera.width;
  st.height = scene.camera.height;
}

namespace {

void requireCpu(const std::string& method, const std::string& backend) {
  if (backend == "gpu")
    throw ConfigError("method '" + method + "' has no GPU variant yet; use --backend cpu");
}

class ExactMethod : public Method {
 public:
  explicit ExactMethod(MarchParams mp) : mp_(mp) {}
  RenderResult render(const Scene& scene, Progress* progress) override {
    RenderResult r;
    fillCpuStats(r.stats, "exact", scene);
    r.density = std::make_shared<const DensityGrid>(buildDensityVolume(scene, r.stats));
    const DensityGrid& density = *r.density;
    if (progress) progress->restart("exact", scene.camera.height);
    {
      ScopedTimer t(r.stats, "march");
      const SourceRadiance source(scene, density, mp_.delta1);
      r.image = marchImage(scene, density, source, mp_.march, progress);
    }
    r.stats.extra["march_step"] = mp_.march.step;
    r.stats.extra["delta1"] = mp_.delta1;
    return r;
  }

 private:
  MarchParams mp_;
};

class PerVoxelMethod : public Method {
 public:
  PerVoxelMethod(MarchParams mp, IVec3 res) : mp_(mp), res_(res) {}
  RenderResult render(const Scene& scene, Progress* progress) override {
    RenderResult r;
    fillCpuStats(r.stats, "per-voxel", scene);
    r.density = std::make_shared<const DensityGrid>(buildDensityVolume(scene, r.stats));
    const DensityGrid& density = *r.density;
    auto radiance = std::make_shared<RadianceGrid>(scene.medium.bounds, res_);
    PerVoxelStats pv;
    {
      ScopedTimer t(r.stats, "radiance");
      if (progress) progress->restart("per-voxel S", res_.z);
      pv = buildPerVoxelRadiance(scene, density, mp_.delta1, *radiance, progress);
    }
    r.image = marchRadianceVolume(scene, density, *radiance, mp_.march, r.stats, progress);
    r.radiance = std::move(radiance);
    r.stats.extra["traced_voxels"] = pv.traced;
    r.stats.extra["empty_voxels"] = pv.skipped;
    r.stats.extra["radiance_resolution"] = {res_.x, res_.y, res_.z};
    r.stats.extra["march_step"] = mp_.march.step;
    r.stats.extra["delta1"] = mp_.delta1;
    return r;
  }

 private:
  MarchParams mp_;
  IVec3 res_;
};

}  // namespace

IVec3 parseRadianceResolution(Params& p, const Scene& scene) {
  if (!p.has("radiance_resolution")) {
    p.allow("radiance_resolution");
    return scene.medium.resolution;
  }
  const Interval range = Interval::closed(1, 4096);
  IVec3 r;
  if (p.json()["radiance_resolution"].is_array()) {
    r = IVec3(p.vec3("radiance_resolution", std::nullopt, range));
  } else {
    r = IVec3(int(p.integer("radiance_resolution", std::nullopt, range)));
  }
  if ((long long)r.x * r.y * r.z > kMaxGridVoxels)
    p.fail("radiance_resolution", "above the memory bound of 512^3 voxels");
  return r;
}

void registerReferenceMethods() {
  methods().add("exact", [](Params& p, const Scene& scene, const std::string& backend) {
    requireCpu("exact", backend);
    return std::unique_ptr<Method>(new ExactMethod(parseMarchParams(p, scene)));
  });
  methods().add("per-voxel", [](Params& p, const Scene& scene, const std::string& backend) {
    requireCpu("per-voxel", backend);
    const MarchParams mp = parseMarchParams(p, scene);
    return std::unique_ptr<Method>(new PerVoxelMethod(mp, parseRadianceResolution(p, scene)));
  });
}

}  // namespace scatterlab
