#pragma once
/// Dense voxel grid over a box with values at cell centres (DESIGN.md §2): voxel (i, j, k) has
/// its centre at min + (i + 1/2, j + 1/2, k + 1/2) * cellSize. Lookups interpolate trilinearly,
/// clamp to the outermost centres inside the box, and return zero outside the box.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/error.h"
#include "core/limits.h"
#include "core/math.h"

namespace scatterlab {

/// Upper bound on voxels of one grid (512³): a larger request throws LimitError instead of
/// trying to allocate gigabytes.
inline constexpr std::int64_t kMaxGridVoxels = std::int64_t(512) * 512 * 512;

template <class T>
class Grid3 {
 public:
  Grid3() = default;
  Grid3(const Box& bounds, IVec3 dims, const T& fill = T(0)) { reset(bounds, dims, fill); }

  void reset(const Box& bounds, IVec3 dims, const T& fill = T(0)) {
    if (dims.x < 1 || dims.y < 1 || dims.z < 1)
      throw ConfigError("grid dimensions must be at least 1 in every axis");
    const std::int64_t n = std::int64_t(dims.x) * dims.y * dims.z;
    if (n > kMaxGridVoxels)
      throw LimitError("grid of " + std::to_string(dims.x) + "x" + std::to_string(dims.y) + "x" +
                       std::to_string(dims.z) + " voxels exceeds the limit of " +
                       std::to_string(kMaxGridVoxels) + " voxels (512^3)");
    checkMemory("grid " + std::to_string(dims.x) + "x" + std::to_string(dims.y) + "x" +
                    std::to_string(dims.z),
                "a volume of " + std::to_string(sizeof(T)) + "-byte voxels", double(n) * sizeof(T));
    bounds_ = bounds;
    dims_ = dims;
    cell_ = bounds.extent() / Vec3(dims);
    invCell_ = Vec3(1.0f) / cell_;
    maxIndex_ = Vec3(dims - 1);
    maxBase_ = glm::max(dims - 2, IVec3(0));
    step_ = IVec3(dims.x > 1 ? 1 : 0, dims.y > 1 ? dims.x : 0, dims.z > 1 ? dims.x * dims.y : 0);
    data_.assign(std::size_t(n), fill);
  }

  const Box& bounds() const { return bounds_; }
  IVec3 dims() const { return dims_; }
  Vec3 cellSize() const { return cell_; }
  std::size_t size() const { return data_.size(); }
  std::size_t index(int i, int j, int k) const {
    return (std::size_t(k) * dims_.y + j) * dims_.x + i;
  }
  Vec3 cellCenter(int i, int j, int k) const {
    return bounds_.min + (Vec3(i, j, k) + 0.5f) * cell_;
  }

  T& at(int i, int j, int k) { return data_[index(i, j, k)]; }
  const T& at(int i, int j, int k) const { return data_[index(i, j, k)]; }
  std::vector<T>& data() { return data_; }
  const std::vector<T>& data() const { return data_; }

  /// Trilinear lookup at world point p; zero outside the box.
  T sample(const Vec3& p) const {
    if (!bounds_.contains(p)) return T(0);
    return sampleIndex((p - bounds_.min) * invCell_ - 0.5f);
  }

  /// Trilinear lookup at continuous index coordinates u (voxel centre i at u = i), clamped to
  /// the outermost centres. Any u is safe (NaN reads voxel 0); callers keep u within the box.
  T sampleIndex(Vec3 u) const {
    // `u > 0 ? u : 0` maps NaN to 0 (a comparison with NaN is false) and compiles to maxss, so
    // no NaN or infinite coordinate can become a wild index (glm::clamp passes NaN through).
    for (int a = 0; a < 3; ++a) {
      u[a] = u[a] > 0.0f ? u[a] : 0.0f;
      u[a] = u[a] < maxIndex_[a] ? u[a] : maxIndex_[a];
    }
    // Base corner clamped to dims-2 so the +1 neighbour exists; along an axis of one voxel the
    // neighbour offset is 0.
    const IVec3 b = glm::min(IVec3(u), maxBase_);
    const Vec3 f = u - Vec3(b);
    const T* p = data_.data() + (std::size_t(b.z) * dims_.y + b.y) * dims_.x + b.x;
    const std::size_t dx = step_.x, dy = step_.y, dz = step_.z;
    const T c00 = p[0] + (p[dx] - p[0]) * f.x;
    const T c10 = p[dy] + (p[dy + dx] - p[dy]) * f.x;
    const T c01 = p[dz] + (p[dz + dx] - p[dz]) * f.x;
    const T c11 = p[dz + dy] + (p[dz + dy + dx] - p[dz + dy]) * f.x;
    const T c0 = c00 + (c10 - c00) * f.y;
    const T c1 = c01 + (c11 - c01) * f.y;
    return c0 + (c1 - c0) * f.z;
  }

  /// World-to-index transform: u = p * scale + offset gives sampleIndex coordinates.
  Vec3 indexScale() const { return invCell_; }
  Vec3 indexOffset() const { return -bounds_.min * invCell_ - 0.5f; }

 private:
  Box bounds_;
  IVec3 dims_{0};
  Vec3 cell_{1.0f}, invCell_{1.0f};
  Vec3 maxIndex_{0.0f};
  IVec3 maxBase_{0}, step_{0};  ///< trilinear base clamp and neighbour strides (0 for 1-voxel axes)
  std::vector<T> data_;
};

using DensityGrid = Grid3<float>;
using RadianceGrid = Grid3<Vec3>;

}  // namespace scatterlab
