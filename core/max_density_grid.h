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
#include "core/math.h"

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
  /// The blocks along one march u_i = u0 + i·du, i in [0, n) (index coordinates of the grid):
  /// an incremental 3D DDA (Amanatides & Woo) over the blocks the ray crosses, in step units.
  class Walk {
   public:
    Walk(const MaxDensityGrid& g, const Vec3& u0, const Vec3& du, int n) : g_(g), u0_(u0), n_(n) {
      for (int a = 0; a < 3; ++a) {
        // `u > 0 ? u : 0` also maps NaN to block 0.
        const float c = u0[a] > 0.0f ? u0[a] * kInvBlock : 0.0f;
        b_[a] = int(std::min(c, float(g.blocks_[a] - 1)));
        dir_[a] = du[a] > 0.0f ? 1 : du[a] < 0.0f ? -1 : 0;
        inv_[a] = dir_[a] != 0 ? 1.0f / du[a] : 0.0f;
        next_[a] = exit(a);
      }
    }
    /// The block of step i (i at or after the previous call's i).
    Span span(int i) {
      // Advance to the first block whose exit lies beyond step i (a block crossed between
      // two steps, at a corner or with steps longer than a block, holds no step).
      for (;;) {
        const int a =
            next_.x <= next_.y ? (next_.x <= next_.z ? 0 : 2) : (next_.y <= next_.z ? 1 : 2);
        if (next_[a] > float(i)) break;
        b_[a] += dir_[a];
        next_[a] = exit(a);
      }
      const float t = std::min(std::min(next_.x, next_.y), std::min(next_.z, float(n_)));
      int end = int(t);  // ceil(t) by conversion (t in [i, n]): std::ceil is a libm call
      end += float(end) < t;
      return {std::min(n_, std::max(i + 1, end)), !(g_.max(b_) > 0.0f)};
    }

   private:
    /// Where the march leaves the current block along axis a (step units): infinity when it
    /// moves away from that face's neighbour or the neighbour is outside the grid (the march
    /// ends at the box face there; lookups clamp to the outermost voxels, which the edge
    /// block holds).
    float exit(int a) const {
      const int nb = b_[a] + dir_[a];
      if (dir_[a] == 0 || nb < 0 || nb >= g_.blocks_[a]) return kInfinity;
      return (float((dir_[a] > 0 ? nb : b_[a]) * kBlock) - u0_[a]) * inv_[a];
    }

    const MaxDensityGrid& g_;
    Vec3 u0_, inv_{0.0f}, next_{0.0f};
    IVec3 b_{0}, dir_{0};
    int n_;
  };

 private:
  static constexpr float kInvBlock = 1.0f / float(kBlock);
  IVec3 blocks_{0};
  std::vector<float> max_;
};

}  // namespace scatterlab
