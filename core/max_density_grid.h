#pragma once
/// Empty-space skipping (issue 14): a coarse grid holding, per block of kBlock³ voxels of a
/// DensityGrid, the largest density any trilinear lookup whose index coordinate lies within one
/// voxel of the block can read. A march in index space (u_i = u0 + i·du, as the CPU marcher and
/// opticalDepth step) walks the blocks with a 3D DDA: it jumps over the steps inside a block
/// whose maximum is zero, where every lookup returns exactly 0, so the skipped steps contribute
/// nothing and images are bit for bit those of the plain march. The one-voxel margin makes the
/// walk robust to the rounding of u0 + i·du against the block faces.

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/grid.h"

namespace scatterlab {

class MaxDensityGrid {
 public:
  static constexpr int kBlock = 8;  ///< voxels per block edge

  MaxDensityGrid() = default;
  /// Scans `g` (TBB over blocks); about 2.6 reads per voxel.
  explicit MaxDensityGrid(const DensityGrid& g);

  IVec3 blocks() const { return blocks_; }
  /// Largest density a lookup at index u with |u − block b| < 1 voxel can return.
  float max(IVec3 b) const { return max_[(std::size_t(b.z) * blocks_.y + b.y) * blocks_.x + b.x]; }

  /// One block along a march: steps [i, end) stay in the block of step i (up to rounding, which
  /// the margin covers), and `empty` says its maximum is zero.
  struct Span {
    int end;
    bool empty;
  };
  /// The blocks along one march u_i = u0 + i·du, i in [0, n) (index coordinates of the grid).
  class Walk {
   public:
    Walk(const MaxDensityGrid& g, const Vec3& u0, const Vec3& du, int n)
        : g_(g), u0_(u0), du_(du), n_(n) {
      for (int a = 0; a < 3; ++a) inv_[a] = du[a] != 0.0f ? 1.0f / du[a] : 0.0f;
    }
    /// The block of step i.
    Span span(int i) const {
      const Vec3 u = u0_ + float(i) * du_;
      IVec3 b;
      float tExit = float(n_);
      for (int a = 0; a < 3; ++a) {
        // `u > 0 ? u : 0` also maps NaN to block 0.
        const float c = u[a] > 0.0f ? u[a] * kInvBlock : 0.0f;
        b[a] = int(std::min(c, float(g_.blocks_[a] - 1)));
        // Leaving towards the outside of the grid only happens at the box face, where the
        // march ends anyway (lookups clamp to the outermost voxels, which the edge block
        // holds).
        if (du_[a] > 0.0f && b[a] + 1 < g_.blocks_[a])
          tExit = std::min(tExit, (float((b[a] + 1) * kBlock) - u0_[a]) * inv_[a]);
        else if (du_[a] < 0.0f && b[a] > 0)
          tExit = std::min(tExit, (float(b[a] * kBlock) - u0_[a]) * inv_[a]);
      }
      const int end = std::min(n_, std::max(i + 1, int(std::ceil(tExit))));
      return {end, !(g_.max(b) > 0.0f)};
    }

   private:
    const MaxDensityGrid& g_;
    Vec3 u0_, du_, inv_;
    int n_;
  };

 private:
  static constexpr float kInvBlock = 1.0f / float(kBlock);
  IVec3 blocks_{0};
  std::vector<float> max_;
};

}  // namespace scatterlab
