#include "cpu/fused_volume.h"

#include <Imath/half.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "core/limits.h"

namespace scatterlab {

bool FusedVolume::compatible(const DensityGrid& d, const RadianceGrid& r) {
  return d.dims() == r.dims() && d.bounds().min == r.bounds().min &&
         d.bounds().max == r.bounds().max && glm::all(glm::greaterThanEqual(d.dims(), IVec3(2)));
}

void FusedVolume::build(const DensityGrid& d, const RadianceGrid& r, bool half) {
  const IVec3 n = d.dims();
  const std::size_t count = d.size();
  checkMemory("render.half_float_volumes",
              std::string("the fast march's fused density + radiance volume (") +
                  (half ? "8" : "16") + "-byte voxels)",
              double(count) * (half ? 8.0 : 16.0));
  for (int a = 0; a < 3; ++a) {
    view_.maxIndex[a] = float(n[a] - 1);
    view_.maxBase[a] = n[a] - 2;
  }
  view_.row = n.x;
  view_.slice = std::ptrdiff_t(n.x) * n.y;
  const float* D = d.data().data();
  const Vec3* S = r.data().data();
  if (!half) {
    if (!f32_ || size_ != 4 * count) {
      f16_.reset();
      f32_.reset();  // before the new one: never both at once
      size_ = 4 * count;
      f32_.reset(new float[size_]);
    }
    view_.f16 = nullptr;
    for (float& c : view_.scale) c = 1.0f;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1 << 14),
                      [&](const tbb::blocked_range<std::size_t>& b) {
                        for (std::size_t i = b.begin(); i < b.end(); ++i) {
                          float* p = &f32_[4 * i];
                          p[0] = D[i];
                          p[1] = S[i].r;
                          p[2] = S[i].g;
                          p[3] = S[i].b;
                        }
                      });
    view_.f32 = f32_.get();
    return;
  }
  // Largest magnitude per channel -> scale so that it is stored as 1024 (half keeps 11
  // significant bits at every magnitude from 6.1e-5 to 65504; values below max · 6e-8 become 0).
  using M = std::array<float, 4>;
  const M mx = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, count, 1 << 14), M{0, 0, 0, 0},
      [&](const tbb::blocked_range<std::size_t>& b, M m) {
        for (std::size_t i = b.begin(); i < b.end(); ++i) {
          m[0] = std::max(m[0], std::abs(D[i]));
          for (int c = 0; c < 3; ++c) m[c + 1] = std::max(m[c + 1], std::abs(S[i][c]));
        }
        return m;
      },
      [](M a, const M& b) {
        for (int c = 0; c < 4; ++c) a[c] = std::max(a[c], b[c]);
        return a;
      });
  float inv[4];
  for (int c = 0; c < 4; ++c) {
    view_.scale[c] = mx[c] > 0.0f && std::isfinite(mx[c]) ? mx[c] / 1024.0f : 1.0f;
    inv[c] = 1.0f / view_.scale[c];
  }
  if (!f16_ || size_ != 4 * count) {
    f32_.reset();
    f16_.reset();
    size_ = 4 * count;
    f16_.reset(new std::uint16_t[size_]);
  }
  view_.f32 = nullptr;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1 << 14),
                    [&](const tbb::blocked_range<std::size_t>& b) {
                      for (std::size_t i = b.begin(); i < b.end(); ++i) {
                        std::uint16_t* p = &f16_[4 * i];
                        p[0] = imath_float_to_half(D[i] * inv[0]);
                        for (int c = 0; c < 3; ++c)
                          p[c + 1] = imath_float_to_half(S[i][c] * inv[c + 1]);
                      }
                    });
  view_.f16 = f16_.get();
}

void FusedVolume::sample(Vec3 u, float out[4]) const {
  const FusedVolumeView& v = view_;
  int b[3];
  float f[3];
  for (int a = 0; a < 3; ++a) {
    u[a] = u[a] > 0.0f ? u[a] : 0.0f;
    u[a] = u[a] < v.maxIndex[a] ? u[a] : v.maxIndex[a];
    b[a] = std::min(int(u[a]), v.maxBase[a]);
    f[a] = u[a] - float(b[a]);
  }
  const std::ptrdiff_t o = 4 * (b[2] * v.slice + b[1] * v.row + b[0]);
  const std::ptrdiff_t dx = 4, dy = 4 * v.row, dz = 4 * v.slice;
  for (int c = 0; c < 4; ++c) {
    const auto at = [&](std::ptrdiff_t k) {
      return v.f32 ? v.f32[o + k + c] : imath_half_to_float(v.f16[o + k + c]);
    };
    const float c00 = at(0) + (at(dx) - at(0)) * f[0];
    const float c10 = at(dy) + (at(dy + dx) - at(dy)) * f[0];
    const float c01 = at(dz) + (at(dz + dx) - at(dz)) * f[0];
    const float c11 = at(dz + dy) + (at(dz + dy + dx) - at(dz + dy)) * f[0];
    const float c0 = c00 + (c10 - c00) * f[1];
    const float c1 = c01 + (c11 - c01) * f[1];
    out[c] = (c0 + (c1 - c0) * f[2]) * v.scale[c];
  }
}

}  // namespace scatterlab
