#pragma once
/// The CPU ray marcher (the integrator stage): for each pixel, march the camera ray through the
/// medium box and sum in-scattering, front to back:
///   L += T · (σs/σt) · (1 − exp(−σt·D·Δt)) · S(x_mid),   T *= exp(−σt·D·Δt),
/// which is exact for D and S constant over each step; then L += T · background, and the
/// pixel's alpha is 1 − T (Image::alpha, for compositing).
/// `source(x, toViewer)` supplies S: traced (exact method) or looked up in a volume.
/// With scene objects, the march stops at the first surface and adds T·L_p (SurfaceRadiance,
/// traced per pixel with step `surfaceDelta1`) instead of T·background, and alpha is 1 (the
/// surface is opaque). camera.spp > 1
/// averages k x k rays (radiance and alpha) through the stratum centres of each pixel.
/// Image::depth records the camera-space depth of the expected first interaction: Σ w·z / A,
/// w = T·(1 − a) per step (z at the step's middle) and T for a surface hit; +∞ where A = 0.
/// With k x k rays the pixel's depth is their alpha-weighted mean.
/// With MarchSettings::fast (render.fast_march, the default) the steps inside blocks of zero
/// density are skipped (MaxDensityGrid: they add exactly nothing), the exp of four steps is
/// taken at once (xsimd; within an ulp of std::exp) and the image is marched in tiles of
/// kMarchTile² pixels (neighbouring rays share cached voxels); the steps taken and the order
/// of their sums are the plain march's. With MarchSettings::scale > 1 (render.march_scale)
/// one ray per scale² pixels is marched and upsampled depth-aware (marchReduced).

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <optional>
#include <type_traits>
#include <xsimd/xsimd.hpp>

#include "core/image.h"
#include "core/max_density_grid.h"
#include "core/progress.h"
#include "core/scene.h"
#include "core/stages.h"
#include "shading/transport.h"

namespace scatterlab {

/// Pixels per tile edge of the fast march.
inline constexpr int kMarchTile = 16;

/// The steps of a view march (stats march_steps, march_steps_skipped), summed over its rays:
/// steps looked up, and steps jumped over in blocks of zero density (the fast march). A run of
/// non-empty blocks that a fused SIMD kernel marches (MarchesSpans) counts whole, also where
/// the ray's transmittance fell below min_transmittance inside it.
struct MarchCounts {
  std::atomic<long long> looked{0}, skipped{0};
};

/// The lookups of one march step for marchImage: D at index coordinates u and, where D > 0,
/// the source S at world point r.at(t) towards the viewer (the step's length dt for a source
/// that integrates over it: the factored march's glow). Returns false where D <= 0 (the step
/// adds nothing). marchWith takes any class with this call operator (a fused volume lookup).
template <class Source>
struct DensitySourceLookup {
  const DensityGrid& density;
  const Source& source;
  bool operator()(const Vec3& u, const Ray& r, float t, float /*dt*/, float& D, Vec3& S) const {
    D = density.sampleIndex(u);
    if (D <= 0.0f) return false;
    S = source(r.at(t), -r.dir);
    return true;
  }
};

/// Whether a lookup class also marches whole runs of steps itself:
///   void marchSpan(const Ray& r, const Vec3& u0, const Vec3& du, float t0, float dt, int i,
///                  int end, Vec3& L, float& T, float& wt) const
/// (steps [i, end) of a run of non-empty blocks, in the order and with the sums of the loop
/// below; the fused volume's SIMD kernels, cpu/fused_march.h). The fast march then calls it
/// once per run.
template <class L, class = void>
struct MarchesSpans : std::false_type {};
template <class L>
struct MarchesSpans<L, std::void_t<decltype(&L::marchSpan)>> : std::true_type {};

/// render.march_scale = s > 1: one ray per s × s block of pixels (through the block's centre),
/// then each pixel takes the depth-aware (joint bilateral) average of the four nearest blocks:
/// bilinear weights times exp(−(|Δz0| + |Δz1|) / σ), z0 and z1 the camera-space depths where
/// the pixel's own ray and the block's ray enter the medium box and leave it (or meet a
/// surface), σ = max(2 voxels, 5 % of the pixel's z1 − z0). The guide costs a box and a surface
/// intersection per pixel, no march. A pixel whose ray misses box and surfaces gets the
/// background exactly (alpha 0); one whose four blocks' similar weight is below half (box
/// edges, surface silhouettes) is marched at full resolution. Radiance, alpha and the depth's
/// Σ w·z are averaged; depth = Σ w·z / alpha as for a marched pixel.
template <class Radiance>
void marchReduced(const Scene& scene, int s, const Radiance& radiance, Image& img,
                  Progress* progress) {
  const Camera& cam = scene.camera;
  const auto rays = cam.rayGenerator();
  Vec3 forward, right, up;
  cam.frame(forward, right, up);
  const int W = cam.width, H = cam.height, w = (W + s - 1) / s, h = (H + s - 1) / s;
  const SceneObjects* objects = scene.objects.get();
  const float voxel = scene.medium.voxelSize();
  // Camera-space entry and exit depths of the medium along r; false where r meets neither the
  // box nor a surface.
  const auto guide = [&](const Ray& r, float& z0, float& z1) {
    SurfaceHit hit;
    const bool hasHit = objects && objects->intersect(r, 0.0f, kInfinity, hit);
    const float c = glm::dot(r.dir, forward);
    float t0, t1;
    if (scene.medium.bounds.intersect(r, t0, t1) && t1 > t0) {
      t0 = std::max(t0, 0.0f);
      if (hasHit) t1 = std::min(t1, hit.t);
      if (hasHit && t0 > t1) t0 = t1;
      z0 = t0 * c;
      z1 = t1 * c;
      return true;
    }
    if (!hasHit) return false;
    z0 = z1 = hit.t * c;
    return true;
  };
  struct Block {
    Vec3 L;
    float alpha, wz, z0, z1;
    bool in;
  };
  std::vector<Block> low(std::size_t(w) * h);
  tbb::parallel_for(
      tbb::blocked_range2d<int>(0, h, kMarchTile, 0, w, kMarchTile),
      [&](const tbb::blocked_range2d<int>& b) {
        for (int y = b.rows().begin(); y < b.rows().end(); ++y)
          for (int x = b.cols().begin(); x < b.cols().end(); ++x) {
            // Centre of the block (clipped at the image's edge).
            const float cx = 0.5f * float(x * s + std::min(W, (x + 1) * s));
            const float cy = 0.5f * float(y * s + std::min(H, (y + 1) * s));
            const Ray r = rays.at(cx, cy);
            const auto sh = radiance(r);
            Block& o = low[std::size_t(y) * w + x];
            o.L = sh.L;
            o.alpha = sh.alpha;
            o.wz = sh.wt * glm::dot(r.dir, forward);
            o.in = guide(r, o.z0, o.z1);
          }
        if (progress && b.cols().end() == w) progress->advance(b.rows().size() * s);
      },
      tbb::simple_partitioner());
  tbb::parallel_for(tbb::blocked_range<int>(0, H, 4), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < W; ++x) {
        const std::size_t at = std::size_t(y) * W + x;
        const Ray r = rays(x, y);
        float z0, z1;
        Vec3 L;
        float alpha, wz;
        if (!guide(r, z0, z1)) {
          L = scene.background;
          alpha = wz = 0.0f;
        } else {
          // The block centres around the pixel centre, in block units.
          const float fx = std::max(0.0f, (float(x) + 0.5f) / float(s) - 0.5f);
          const float fy = std::max(0.0f, (float(y) + 0.5f) / float(s) - 0.5f);
          const int x0 = std::min(int(fx), w - 1), y0 = std::min(int(fy), h - 1);
          const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
          const float ax = fx - float(x0), ay = fy - float(y0);
          const float sigma = std::max(2.0f * voxel, 0.05f * (z1 - z0));
          const int bx[4] = {x0, x1, x0, x1}, by[4] = {y0, y0, y1, y1};
          const float bw[4] = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
          float sum = 0.0f;
          L = Vec3(0.0f);
          alpha = wz = 0.0f;
          for (int q = 0; q < 4; ++q) {
            const Block& o = low[std::size_t(by[q]) * w + bx[q]];
            if (!o.in || bw[q] <= 0.0f) continue;
            const float wq = bw[q] * std::exp(-(std::abs(o.z0 - z0) + std::abs(o.z1 - z1)) / sigma);
            sum += wq;
            L += wq * o.L;
            alpha += wq * o.alpha;
            wz += wq * o.wz;
          }
          if (sum >= 0.5f) {
            L /= sum;
            alpha /= sum;
            wz /= sum;
          } else {
            const auto sh = radiance(r);
            L = sh.L;
            alpha = sh.alpha;
            wz = sh.wt * glm::dot(r.dir, forward);
          }
        }
        img.pixels()[at] = L;
        img.alpha()[at] = alpha;
        img.depth()[at] = alpha > 0.0f ? wz / alpha : std::numeric_limits<float>::infinity();
      }
  });
}

/// marchImage with the per-step lookups of `lookup` (DensitySourceLookup's interface); `density`
/// gives the index space of u, the skipping grid and the surfaces' transmittance.
/// `counts` (optional): the steps looked up and jumped over.
template <class Lookup>
Image marchWith(const Scene& scene, const DensityGrid& density, const Lookup& lookup,
                const MarchSettings& ms, Progress* progress, float surfaceDelta1 = 0.0f,
                MarchCounts* counts = nullptr) {
  const Camera& cam = scene.camera;
  const auto rays = cam.rayGenerator();
  const Medium& m = scene.medium;
  const float sigmaT = m.sigmaT, ratio = m.albedo;  // σs/σt = Ω
  const float minT = ms.minTransmittance;
  const SceneObjects* objects = scene.objects.get();
  const SurfaceRadiance surface(scene, density, surfaceDelta1 > 0.0f ? surfaceDelta1 : ms.step);
  std::optional<MaxDensityGrid> skip;
  if (ms.fast && sigmaT > 0.0f) skip.emplace(density);
  // One camera ray: in-scattering up to the first surface (or the box exit), then T·L_p of
  // the surface or T·background.
  // Radiance and alpha: 1 − T of the medium, 1 where an (opaque) surface is hit.
  // Radiance, alpha and Σ w·t (the opacity-weighted ray distance of the interactions).
  struct Shaded {
    Vec3 L;
    float alpha;
    float wt;
  };
  const auto radiance = [&](const Ray& r) -> Shaded {
    Vec3 L(0.0f);
    float T = 1.0f, wt = 0.0f;
    SurfaceHit hit;
    const bool hasHit = objects && objects->intersect(r, 0.0f, kInfinity, hit);
    float t0, t1;
    if (sigmaT > 0.0f && m.bounds.intersect(r, t0, t1) && t1 > t0) {
      if (hasHit) t1 = std::min(t1, hit.t);
      if (t1 > t0) {
        const int n = stepCount(t1 - t0, ms.step);
        const float dt = (t1 - t0) / float(n);
        const Vec3 s = density.indexScale();
        const Vec3 u0 = r.at(t0 + 0.5f * dt) * s + density.indexOffset();
        const Vec3 du = r.dir * dt * s;
        const auto step = [&](int i) {
          float D;
          Vec3 S;
          if (!lookup(u0 + float(i) * du, r, t0 + (float(i) + 0.5f) * dt, dt, D, S)) return;
          const float a = std::exp(-sigmaT * D * dt);
          L += (T * ratio * (1.0f - a)) * S;
          wt += T * (1.0f - a) * (t0 + (float(i) + 0.5f) * dt);
          T *= a;
        };
        long long looked = 0, skipped = 0;
        if (!skip) {
          for (int i = 0; i < n && T > minT; ++i, ++looked) step(i);
        } else {
          // 3D DDA over the blocks: jump the empty ones, march the others in groups of four
          // steps: four lookups, one 4-wide exp (xsimd), then the four sums in order.
          using Batch = xsimd::make_sized_batch_t<float, 4>;
          MaxDensityGrid::Walk walk(*skip, u0, du, n);
          for (int i = 0; i < n && T > minT;) {
            const MaxDensityGrid::Span sp = walk.span(i);
            if constexpr (MarchesSpans<Lookup>::value) {
              // One call per run of non-empty blocks (the same steps in the same order; fewer
              // calls and partial groups of steps in the kernel).
              if (sp.empty) {
                skipped += sp.end - i;
                i = sp.end;
                continue;
              }
              int e = sp.end, next = e;
              while (e < n) {
                const MaxDensityGrid::Span nx = walk.span(e);
                if (nx.empty) {
                  next = nx.end;
                  break;
                }
                e = next = nx.end;
              }
              lookup.marchSpan(r, u0, du, t0, dt, i, e, L, T, wt);
              looked += e - i;
              skipped += next - e;
              i = next;
              continue;
            }
            for (; !sp.empty && i < sp.end && T > minT; i += 4) {
              const int q1 = std::min(4, sp.end - i);
              looked += q1;
              alignas(16) float D[4] = {0.0f, 0.0f, 0.0f, 0.0f}, a[4];
              Vec3 S[4];
              for (int q = 0; q < q1; ++q)
                if (!lookup(u0 + float(i + q) * du, r, t0 + (float(i + q) + 0.5f) * dt, dt, D[q],
                            S[q]))
                  D[q] = 0.0f;
              xsimd::exp(Batch(-sigmaT) * Batch::load_aligned(D) * Batch(dt)).store_aligned(a);
              for (int q = 0; q < q1 && T > minT; ++q) {
                if (!(D[q] > 0.0f)) continue;
                L += (T * ratio * (1.0f - a[q])) * S[q];
                wt += T * (1.0f - a[q]) * (t0 + (float(i + q) + 0.5f) * dt);
                T *= a[q];
              }
            }
            if (sp.empty) skipped += sp.end - i;
            i = sp.end;
          }
        }
        if (counts) {
          counts->looked.fetch_add(looked, std::memory_order_relaxed);
          counts->skipped.fetch_add(skipped, std::memory_order_relaxed);
        }
      }
    }
    if (!hasHit) return {L + T * scene.background, 1.0f - T, wt};
    // Below min_transmittance the surface's share is below it too (as for the medium).
    return {T > minT ? L + T * surface(hit) : L, 1.0f, wt + T * hit.t};
  };
  Vec3 forward, right, up;
  cam.frame(forward, right, up);
  // Camera-space depth of the pixel from its rays' alpha and Σ w·t (t along each unit ray).
  const auto depthOf = [](float alpha, float wz) {
    return alpha > 0.0f ? wz / alpha : std::numeric_limits<float>::infinity();
  };
  const int k = std::max(1, int(std::lround(std::sqrt(double(cam.spp)))));
  const float inv = 1.0f / float(k * k);
  Image img(cam.width, cam.height);
  img.alpha().assign(img.pixels().size(), 0.0f);
  img.depth().assign(img.pixels().size(), 0.0f);
  const auto pixel = [&](int x, int y) {
    const size_t at = size_t(y) * cam.width + x;
    if (k == 1) {
      const Ray r = rays(x, y);
      const Shaded sh = radiance(r);
      img.at(x, y) = sh.L;
      img.alpha()[at] = sh.alpha;
      img.depth()[at] = depthOf(sh.alpha, sh.wt * glm::dot(r.dir, forward));
      return;
    }
    // k x k stratum centres, box filter.
    Vec3 sum(0.0f);
    float alpha = 0.0f, wz = 0.0f;
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < k; ++i) {
        const Ray r = rays.at(float(x) + (float(i) + 0.5f) / float(k),
                              float(y) + (float(j) + 0.5f) / float(k));
        const Shaded sh = radiance(r);
        sum += sh.L;
        alpha += sh.alpha;
        wz += sh.wt * glm::dot(r.dir, forward);
      }
    img.at(x, y) = sum * inv;
    img.alpha()[at] = alpha * inv;
    img.depth()[at] = depthOf(alpha, wz);
  };
  if (ms.scale > 1 && k == 1) {
    marchReduced(scene, ms.scale, radiance, img, progress);
    return img;
  }
  // Rows (the plain march) or tiles; progress counts rows, a tile adds its share of one.
  const int tile = ms.fast ? kMarchTile : cam.width;
  const int rowGrain = ms.fast ? kMarchTile : 1;
  tbb::parallel_for(
      tbb::blocked_range2d<int>(0, cam.height, rowGrain, 0, cam.width, tile),
      [&](const tbb::blocked_range2d<int>& b) {
        for (int y = b.rows().begin(); y < b.rows().end(); ++y)
          for (int x = b.cols().begin(); x < b.cols().end(); ++x) pixel(x, y);
        if (progress && b.cols().end() == cam.width) progress->advance(b.rows().size());
      },
      tbb::simple_partitioner());
  return img;
}

template <class Source>
Image marchImage(const Scene& scene, const DensityGrid& density, const Source& source,
                 const MarchSettings& ms, Progress* progress, float surfaceDelta1 = 0.0f,
                 MarchCounts* counts = nullptr) {
  return marchWith(scene, density, DensitySourceLookup<Source>{density, source}, ms, progress,
                   surfaceDelta1, counts);
}

}  // namespace scatterlab
