#pragma once
/// A's far field on the CPU (render.far_field; FarField in shading/transport.h, docs/gpu.md "A's
/// far field on a grid"): the grid of the point lights' far terms, kept by the factored march
/// from render to render and brought up to date with as little work as the change allows.

#include <cstdint>
#include <memory>
#include <vector>

#include "core/grid.h"
#include "core/scene.h"
#include "shading/transport.h"

namespace scatterlab {

/// The far field of the lights the factored march last rendered, over the bricks of the volume
/// that hold density. The march looks the grid up only at steps with density (D > 0), which lie
/// in voxels next to a non-zero one: vertices of 8³-voxel bricks with no density within a voxel
/// are never read, are not computed and stay 0. Between renders:
///  * nothing it depends on changed (a camera move: the far field is isotropic): kept;
///  * some of the point lights moved or changed (at most half of them, the bricks and R the
///    same): updated in place, each changed light's old term taken out of the sums and its new
///    one put in (2 terms per vertex and changed light instead of one per light), rebuilt
///    whole after kMaxUpdates updates so that rounding does not accumulate;
///  * else built anew.
class FarFieldCache {
 public:
  /// Updates in a row before a whole build (each adds a rounding of the sums, ~1e-7 relative).
  static constexpr int kMaxUpdates = 16;

  /// The grid for `scene`'s lights with `lamp` (A's near-lamp model) over `density`, R =
  /// radiusVoxels voxels of the medium. `terms` (may be null): point-light terms evaluated,
  /// added to it. The same density object as last time (a frame that kept its density: a
  /// host frame's density is a new object whenever it is built) keeps the live bricks found in
  /// it instead of scanning it again.
  const FarField& update(const Scene& scene, const LampModel& lamp,
                         const std::shared_ptr<const DensityGrid>& density, float radiusVoxels,
                         long long* terms = nullptr);
  const FarField& grid() const { return grid_; }

 private:
  /// Whether some voxel within one voxel of each 8³ brick of cells holds density (x fastest).
  static std::vector<std::uint8_t> liveBricks(const DensityGrid& density, const IVec3& bricks);
  /// Calls f(i, j, k, index) for every vertex next to a live brick, the layers in parallel;
  /// returns how many.
  template <class F>
  long long forLiveVertices(const F& f) const;

  FarField grid_;
  float radiusVoxels_ = 0.0f;
  Box box_;
  IVec3 resolution_{0};
  IVec3 bricks_{0};
  std::vector<std::uint8_t> live_;
  std::weak_ptr<const DensityGrid> density_;  ///< the density live_ was found in
  std::vector<Light> lights_;                 ///< the lights the sums hold
  LampModel lamp_;                            ///< and their lamp model
  int updates_ = 0;                           ///< in-place updates since the last whole build
};

}  // namespace scatterlab
