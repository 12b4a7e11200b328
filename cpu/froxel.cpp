#include "cpu/froxel.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <chrono>

#include "cpu/screen_compose.h"
#include "shading/transport.h"

namespace scatterlab {

TransmittanceMaps::TransmittanceMaps(const Scene& scene, const DensityGrid& density, int resolution,
                                     float delta1)
    : scene_(scene) {
  const SceneObjects* objects = scene.objects.get();
  const float sigmaT = scene.medium.sigmaT;
  for (const Light& l : scene.lights) {
    DensityGrid map(density.bounds(), IVec3(resolution), 0.0f);
    tbb::parallel_for(0, resolution, [&](int k) {
      for (int j = 0; j < resolution; ++j)
        for (int i = 0; i < resolution; ++i) {
          const Vec3 x = map.cellCenter(i, j, k);
          // The transmittance whether or not x is inside a spot's cone (the source weights it
          // by the cone), so that the map interpolates smoothly across the cone's edge.
          Light::Geometry g;
          if (!l.geometry(x, g)) continue;
          Light::Incident inc;
          inc.toLight = g.toLight;
          inc.distance = g.distance;
          if (objects && objects->occluded(x, inc.toLight, 0.0f, inc.distance)) continue;
          const float tau =
              opticalDepth(density, x, lightSegmentEnd(l, inc, density.bounds(), x), delta1);
          map.at(i, j, k) = std::exp(-sigmaT * tau);
        }
    });
    maps_.push_back(std::move(map));
  }
}

Vec3 TransmittanceMaps::source(const Vec3& x, const Vec3& toViewer) const {
  Vec3 s(0.0f);
  for (size_t li = 0; li < scene_.lights.size(); ++li) {
    Light::Incident inc;
    if (!scene_.lights[li].incident(x, inc)) continue;
    s += inc.irradiance * (scene_.medium.phase.eval(-inc.toLight, toViewer) * maps_[li].sample(x));
  }
  return s;
}

namespace {

/// The ray of froxel column (i, j).
Ray columnRay(const Camera::RayGenerator& rays, IVec3 dims, int i, int j) {
  return rays.at((float(i) + 0.5f) * float(rays.width) / float(dims.x),
                 (float(j) + 0.5f) * float(rays.height) / float(dims.y));
}

}  // namespace

FroxelVolume froxelAccumulate(const Scene& scene, const DensityGrid& density,
                              const FroxelSettings& s, float delta1,
                              const TransmittanceMaps* maps) {
  FroxelVolume v;
  v.dims = s.grid;
  v.slicing = froxelSlicing(scene, s);
  const size_t n = size_t(v.dims.x) * v.dims.y * v.dims.z;
  v.L.assign(n, Vec3(0.0f));
  v.T.assign(n, 1.0f);
  const auto rays = scene.camera.rayGenerator();
  const Medium& m = scene.medium;
  const SourceRadiance traced(scene, density, delta1);
  const Vec3 sc = density.indexScale(), so = density.indexOffset();
  tbb::parallel_for(0, v.dims.y, [&](int j) {
    for (int i = 0; i < v.dims.x; ++i) {
      const Ray ray = columnRay(rays, v.dims, i, j);
      const float c = glm::dot(ray.dir, rays.forward);
      // The column's piece inside the medium box: each slice is clipped to it, so that a slice
      // across a face counts only its part inside, and no froxel's centre sits on a face,
      // where which side it falls on is a matter of rounding (CPU ≠ GPU).
      float t0 = 0.0f, t1 = -1.0f;
      if (m.sigmaT > 0.0f && !m.bounds.intersect(ray, t0, t1)) t1 = -1.0f;
      Vec3 L(0.0f);
      float T = 1.0f;
      for (int k = 0; k < v.dims.z; ++k) {
        const float za = v.slicing.depth(float(k)), zb = v.slicing.depth(float(k + 1));
        const float ta = std::max(za / c, t0), tb = std::min(zb / c, t1);
        const Vec3 x = ray.at(0.5f * (ta + tb));
        const float D = tb > ta ? density.sampleIndex(x * sc + so) : 0.0f;
        if (D > 0.0f) {
          const float a = std::exp(-m.sigmaT * D * (tb - ta));
          const Vec3 S = maps ? maps->source(x, -ray.dir) : traced(x, -ray.dir);
          L += (T * m.albedo * (1.0f - a)) * S;
          T *= a;
        }
        v.L[v.index(i, j, k)] = L;
        v.T[v.index(i, j, k)] = T;
      }
    }
  });
  return v;
}

void froxelLookup(const FroxelVolume& v, const Camera::RayGenerator& rays, int x, int y,
                  const Ray& ray, float tEnd, Vec3& L, float& T) {
  const float z = std::isinf(tEnd) ? v.slicing.far : tEnd * glm::dot(ray.dir, rays.forward);
  const float w = v.slicing.coordinate(z);  // boundary coordinate in [0, nz]
  const float gx = std::clamp((float(x) + 0.5f) / float(rays.width) * float(v.dims.x) - 0.5f, 0.0f,
                              float(v.dims.x - 1));
  const float gy = std::clamp((float(y) + 0.5f) / float(rays.height) * float(v.dims.y) - 0.5f, 0.0f,
                              float(v.dims.y - 1));
  const int i0 = std::min(int(gx), v.dims.x - 1), j0 = std::min(int(gy), v.dims.y - 1);
  const int i1 = std::min(i0 + 1, v.dims.x - 1), j1 = std::min(j0 + 1, v.dims.y - 1);
  const int b0 = std::min(int(w), v.dims.z - 1);
  const float fx = gx - float(i0), fy = gy - float(j0), fz = w - float(b0);
  L = Vec3(0.0f);
  T = 0.0f;
  // Boundary b holds (L, T) after slice b − 1; boundary 0 is (0, 1).
  const auto add = [&](int i, int j, int b, float weight) {
    if (weight == 0.0f) return;
    if (b == 0) {
      T += weight;
      return;
    }
    const size_t p = v.index(i, j, b - 1);
    L += weight * v.L[p];
    T += weight * v.T[p];
  };
  for (int c = 0; c < 8; ++c) {
    const int i = (c & 1) ? i1 : i0, j = (c & 2) ? j1 : j0, b = (c & 4) ? b0 + 1 : b0;
    const float weight =
        ((c & 1) ? fx : 1 - fx) * ((c & 2) ? fy : 1 - fy) * ((c & 4) ? fz : 1 - fz);
    add(i, j, b, weight);
  }
}

Image froxelRender(const Scene& scene, const DensityGrid& density, const FroxelSettings& s,
                   float delta1, float minTransmittance, Progress* progress, Json* passMs) {
  using Clock = std::chrono::steady_clock;
  const auto ms = [](Clock::time_point a) {
    return std::chrono::duration<double, std::milli>(Clock::now() - a).count();
  };
  auto t = Clock::now();
  std::unique_ptr<TransmittanceMaps> maps;
  if (s.transmittanceMap) {
    maps = std::make_unique<TransmittanceMaps>(scene, density, s.mapResolution, delta1);
    if (passMs) (*passMs)["transmittance_map"] = ms(t);
    t = Clock::now();
  }
  if (progress) progress->restart("froxel", 1);
  const FroxelVolume v = froxelAccumulate(scene, density, s, delta1, maps.get());
  if (passMs) (*passMs)["froxel_accumulate"] = ms(t);
  t = Clock::now();
  const auto rays = scene.camera.rayGenerator();
  Image img = composeScreen(scene, density, delta1, minTransmittance,
                            [&](int x, int y, const Ray& ray, const SurfaceHit* hit) {
                              PixelMedium m;
                              froxelLookup(v, rays, x, y, ray, hit ? hit->t : kInfinity, m.L, m.T);
                              return m;
                            });
  if (passMs) (*passMs)["froxel_lookup"] = ms(t);
  if (progress) progress->advance(1);
  return img;
}

}  // namespace scatterlab
