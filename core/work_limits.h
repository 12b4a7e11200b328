#pragma once
/// Limits on one render as a whole, checked before it starts (docs/reliability.md, "Resource
/// limits" and "Work bounds"): the sum of its planned allocations against the memory limit of
/// core/limits.h, and the bounds on marching work. Kept apart from core/limits.h (which every
/// grid includes) so that a change here recompiles only its few users.

#include <string>
#include <vector>

namespace scatterlab {

/// The sum of one render's planned allocations (volumes, images, sample sets, hash tables,
/// fused volumes, the max-density grid), compared with memoryLimit() as a whole before the
/// render starts: each one may be below the limit while together they are not.
class MemoryPlan {
 public:
  /// One planned allocation: `keys` the dotted keys (or file) whose values imply it, `what`
  /// what it is ("the density volume of 64x64x64 voxels"). Sizes <= 0 are not recorded.
  void add(std::vector<std::string> keys, const std::string& what, double bytes);
  void add(const std::string& key, const std::string& what, double bytes) {
    add(std::vector<std::string>{key}, what, bytes);
  }
  double total() const;
  /// Throws LimitError when total() exceeds memoryLimit(), naming the total, the limit and
  /// the largest contributors (at most three, largest first, with their keys).
  void check() const;

  struct Item {
    std::vector<std::string> keys;
    std::string what;
    double bytes = 0;
  };
  const std::vector<Item>& items() const { return items_; }

 private:
  std::vector<Item> items_;
};

/// Bounds on work, checked before a render starts (methods/settings.cpp, docs/reliability.md):
/// view-ray steps (pixels × spp × ⌈diagonal / march_step⌉) and light-march (volume-tracing)
/// steps, each ⌈diagonal / delta1⌉ × lights long: per view step (exact), per voxel
/// (per-voxel), and per traced point of the samples (S, the 6 central differences of ∇S, the
/// probes of dynamic sampling). 1e10 view steps take minutes on a few cores.
inline constexpr double kMaxViewSteps = 1e10;
inline constexpr double kMaxLightSteps = 1e12;

/// A count or size in messages, three significant digits ("1.02e+10", "320").
std::string formatCount(double v);

}  // namespace scatterlab
