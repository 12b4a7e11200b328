/// FarFieldCache (cpu/far_field.h): A's far field on the CPU, built, updated or kept.

#include "cpu/far_field.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <xsimd/xsimd.hpp>

#include "core/stages.h"

namespace scatterlab {

namespace {

/// Whether light a and light b (with lamp-model k ka, kb) give the same far terms: a point
/// light's by its position, intensity and k; any other light's are 0.
bool sameFarPart(const Light& a, float ka, const Light& b, float kb) {
  if (a.type != b.type) return false;
  if (a.type != Light::Type::Point) return true;
  return a.position == b.position && a.intensity == b.intensity && ka == kb;
}

using Batch = xsimd::batch<float>;  // the build's baseline width (4 lanes with SSE2)

/// Point lights laid out for farSum: structure of arrays, padded to whole batches with lights
/// of intensity 0.
struct FarLights {
  std::vector<float> px, py, pz, ir, ig, ib, k;
  bool lamp = false;  ///< some k > 0: the lamp model's m_l evaluated
  /// Point light l with its lamp-model k, its intensity times `sign` (−1: its terms taken out).
  void add(const Light& l, float kl, float sign) {
    if (l.type != Light::Type::Point) return;  // w = 0: not in the far field
    px.push_back(l.position.x);
    py.push_back(l.position.y);
    pz.push_back(l.position.z);
    ir.push_back(sign * l.intensity.x);
    ig.push_back(sign * l.intensity.y);
    ib.push_back(sign * l.intensity.z);
    k.push_back(kl);
    lamp |= kl > 0.0f;
  }
  /// Padding: 1e15 from every vertex (w = 1; d² 1e30, finite; k·distance 0), intensity 0.
  void pad() {
    while (px.size() % Batch::size) {
      for (auto* v : {&ir, &ig, &ib, &k}) v->push_back(0.0f);
      for (auto* v : {&px, &py, &pz}) v->push_back(1e15f);
    }
  }
};

/// Σ_l w_l·A_l at x over `L` (LightFactor's terms for the isotropic phase: w·I·m/(4π d²),
/// w = FarField::weight, m the lamp model), Batch::size lights at a time.
Vec3 farSum(const FarLights& L, const Vec3& x, float R) {
  const Batch X(x.x), Y(x.y), Z(x.z), r(R), zero(0.0f), one(1.0f);
  Batch s0(0.0f), s1(0.0f), s2(0.0f);
  for (std::size_t j = 0; j < L.px.size(); j += Batch::size) {
    const Batch dx = Batch::load_unaligned(&L.px[j]) - X, dy = Batch::load_unaligned(&L.py[j]) - Y,
                dz = Batch::load_unaligned(&L.pz[j]) - Z;
    const Batch d2 = dx * dx + dy * dy + dz * dz;
    const Batch dist = xsimd::sqrt(d2);
    const Batch u = xsimd::min(xsimd::max((dist - r) / r, zero), one);
    Batch f = u * u * (Batch(3.0f) - Batch(2.0f) * u) * Batch(kInvFourPi) / d2;
    if (L.lamp) {
      const Batch q = Batch::load_unaligned(&L.k[j]) * dist;
      f *= lampTransmittance(q);
    }
    f = xsimd::select(d2 > zero, f, zero);  // Light::incident: nothing at the light itself
    s0 += Batch::load_unaligned(&L.ir[j]) * f;
    s1 += Batch::load_unaligned(&L.ig[j]) * f;
    s2 += Batch::load_unaligned(&L.ib[j]) * f;
  }
  return Vec3(xsimd::hadd(s0), xsimd::hadd(s1), xsimd::hadd(s2));
}

}  // namespace

std::vector<std::uint8_t> FarFieldCache::liveBricks(const DensityGrid& density,
                                                    const IVec3& bricks) {
  const IVec3 n = density.dims();
  std::vector<std::uint8_t> live(std::size_t(bricks.x) * std::size_t(bricks.y) *
                                 std::size_t(bricks.z));
  // A point in cell c reads the voxels c − 1 … c + 1 (voxel centres at the cells' centres).
  tbb::parallel_for(0, bricks.z, [&](int bz) {
    for (int by = 0; by < bricks.y; ++by)
      for (int bx = 0; bx < bricks.x; ++bx) {
        const IVec3 b(bx, by, bz);
        const IVec3 lo = glm::max(b * kFarBrick - 1, IVec3(0));
        const IVec3 hi = glm::min(b * kFarBrick + kFarBrick, n - 1);
        bool any = false;
        for (int z = lo.z; z <= hi.z && !any; ++z)
          for (int y = lo.y; y <= hi.y && !any; ++y)
            for (int x = lo.x; x <= hi.x && !any; ++x) any = density.at(x, y, z) > 0.0f;
        live[(std::size_t(bz) * std::size_t(bricks.y) + std::size_t(by)) * std::size_t(bricks.x) +
             std::size_t(bx)] = any;
      }
  });
  return live;
}

template <class F>
long long FarFieldCache::forLiveVertices(const F& f) const {
  const IVec3 dims = grid_.dims, last = bricks_ - 1;
  // Vertex i is a corner of cells i − 1 and i, in bricks (i − 1) / 8 and i / 8.
  const auto brickPair = [](int i, int lastBrick) {
    return std::array<int, 2>{std::clamp((i - 1) / kFarBrick, 0, lastBrick),
                              std::clamp(i / kFarBrick, 0, lastBrick)};
  };
  const auto liveAt = [&](int x, int y, int z) {
    return live_[(std::size_t(z) * std::size_t(bricks_.y) + std::size_t(y)) *
                     std::size_t(bricks_.x) +
                 std::size_t(x)] != 0;
  };
  std::atomic<long long> count{0};
  tbb::parallel_for(0, dims.z, [&](int k) {
    const auto bz = brickPair(k, last.z);
    long long layer = 0;
    for (int j = 0; j < dims.y; ++j) {
      const auto by = brickPair(j, last.y);
      for (int i = 0; i < dims.x; ++i) {
        const auto bx = brickPair(i, last.x);
        bool needed = false;
        for (int c = 0; c < 8 && !needed; ++c)
          needed = liveAt(bx[c & 1], by[(c >> 1) & 1], bz[c >> 2]);
        if (!needed) continue;
        f(i, j, k,
          (std::size_t(k) * std::size_t(dims.y) + std::size_t(j)) * std::size_t(dims.x) +
              std::size_t(i));
        ++layer;
      }
    }
    count.fetch_add(layer, std::memory_order_relaxed);
  });
  return count.load();
}

const FarField& FarFieldCache::update(const Scene& scene, const LampModel& lamp,
                                      const std::shared_ptr<const DensityGrid>& density,
                                      float radiusVoxels, long long* terms) {
  const Medium& m = scene.medium;
  const IVec3 bricks = (m.resolution + IVec3(kFarBrick - 1)) / kFarBrick;
  // A density of other dimensions than the medium's cells: every brick read.
  std::vector<std::uint8_t> live =
      density_.lock() == density && m.resolution == resolution_ && !live_.empty() ? live_
      : density->dims() == m.resolution
          ? liveBricks(*density, bricks)
          : std::vector<std::uint8_t>(std::size_t(bricks.x) * bricks.y * bricks.z, 1);
  density_ = density;
  const std::vector<Light>& lights = scene.lights;
  const bool sameGrid = grid_.on() && radiusVoxels == radiusVoxels_ && m.bounds.min == box_.min &&
                        m.bounds.max == box_.max && m.resolution == resolution_ && live == live_ &&
                        lights.size() == lights_.size() && lamp.on() == lamp_.on();
  // The lights whose far terms changed; a light that changed its type: build anew.
  std::vector<std::size_t> changed;
  bool typeChanged = false;
  if (sameGrid)
    for (std::size_t l = 0; l < lights.size(); ++l)
      if (!sameFarPart(lights[l], lamp.k(l), lights_[l], lamp_.k(l))) {
        changed.push_back(l);
        typeChanged |= lights[l].type != lights_[l].type;
      }
  // The terms of L added to every live vertex's sum (a whole build's start at 0); the terms
  // evaluated.
  const auto addToGrid = [&](FarLights L) {
    const long long n = static_cast<long long>(L.px.size());
    L.pad();
    return n * forLiveVertices([&](int i, int j, int k, std::size_t v) {
             grid_.a[v] += farSum(L, grid_.lo + Vec3(float(i), float(j), float(k)) * grid_.cell,
                                  grid_.radius);
           });
  };
  long long evaluated = 0;
  if (sameGrid && changed.empty()) {
    // kept
  } else if (sameGrid && !typeChanged && 2 * changed.size() <= lights.size() &&
             updates_ < kMaxUpdates) {
    // The changed lights' new terms in, their old ones out (intensity × −1).
    FarLights L;
    for (const std::size_t l : changed) L.add(lights[l], lamp.k(l), 1.0f);
    for (const std::size_t l : changed) L.add(lights_[l], lamp_.k(l), -1.0f);
    evaluated = addToGrid(std::move(L));
    ++updates_;
  } else {
    grid_ = FarField();
    grid_.radius = radiusVoxels * m.voxelSize();
    grid_.dims = m.resolution + IVec3(1);
    grid_.lo = m.bounds.min;
    grid_.cell = m.bounds.extent() / Vec3(m.resolution);
    grid_.a.assign(
        std::size_t(grid_.dims.x) * std::size_t(grid_.dims.y) * std::size_t(grid_.dims.z),
        Vec3(0.0f));
    radiusVoxels_ = radiusVoxels;
    box_ = m.bounds;
    resolution_ = m.resolution;
    bricks_ = bricks;
    live_ = std::move(live);
    FarLights L;
    for (std::size_t l = 0; l < lights.size(); ++l) L.add(lights[l], lamp.k(l), 1.0f);
    evaluated = addToGrid(std::move(L));
    updates_ = 0;
  }
  lights_ = lights;
  lamp_ = lamp;
  if (terms) *terms += evaluated;
  return grid_;
}

}  // namespace scatterlab
