#pragma once
/// Stage interface: the density model (DESIGN.md §3). A model gives D(x) >= 0 in world space
/// and builds the dense density volume the renderers march through. Implementations live in
/// media/ and are registered by registerMediaModels().

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/grid.h"
#include "core/params.h"
#include "core/registry.h"

namespace scatterlab {

/// One Gaussian of a sum-of-Gaussians medium (paper Eq. 3): w·exp(−|x−c|²/r²).
/// Blobs are culled at this many radii r (exp(−9) ≈ 1.2e-4 of the peak), by every backend.
inline constexpr float kGaussianCullRadius = 3.0f;

struct GaussianBlob {
  Vec3 center{0.5f};
  float radius = 0.1f;  ///< r in w·exp(−|x−c|²/r²) (the paper's convention, Eq. 3)
  float weight = 1.0f;
};

class DensityModel {
 public:
  virtual ~DensityModel() = default;

  /// Registry name of the model ("uniform", "gaussians", ...).
  virtual std::string type() const = 0;

  /// Density at world point x (the model's own continuous field, before any resampling).
  /// Thread-safe. A virtual call per point: meant for tests, construction and probes, never
  /// for the renderers' inner loops, which read the volume from build().
  virtual float eval(const Vec3& x) const = 0;

  /// Fills every cell centre of `grid` (bounds and dims already set by the caller) with the
  /// density there. The default evaluates eval() at each centre in parallel (TBB); models with
  /// a faster construction (splatting) override it. No GL context needed.
  virtual void build(DensityGrid& grid) const;

  /// The box the model covers when the scene gives no medium.bounds (a VDB's world bounds).
  virtual std::optional<Box> naturalBounds() const { return std::nullopt; }

  /// The Gaussians of a sum-of-Gaussians model (the paper's initial sample set, Sec. 4), or
  /// null for models that have none. Owned by the model; valid while it lives.
  virtual const std::vector<GaussianBlob>* gaussians() const { return nullptr; }

  /// True when the Gaussians of gaussians() are the whole density (no residual), so a device
  /// can build the volume by splatting them (paper Sec. 6) instead of uploading build()'s.
  virtual bool isSumOfGaussians() const { return false; }

  /// The largest density the model takes (for a sum of up to 4096 Gaussians: the largest of the
  /// sums at the blobs' centres, an estimate), or nullopt where the model does not know it
  /// cheaply.
  /// Decides defaults before any volume is built (render.log_space, methods/settings.cpp).
  virtual std::optional<float> peak() const { return std::nullopt; }

  /// One-line human-readable summary for `scatterlab info`.
  virtual std::string describe() const = 0;
};

/// Where relative paths in a scene resolve from.
struct LoadContext {
  std::filesystem::path baseDir;
  std::optional<Box> mediumBounds;  ///< medium.bounds when the scene gives it
  std::filesystem::path resolve(const std::string& p) const {
    const std::filesystem::path q(p);
    return q.is_absolute() ? q : baseDir / q;
  }
};

/// Reads its own keys from `params` (the medium.density object; "type" is already read) and
/// returns the model. Must not call params.finish(); the caller does.
using DensityModelFactory =
    std::function<std::unique_ptr<DensityModel>(Params& params, const LoadContext& ctx)>;

Registry<DensityModelFactory>& densityModels();

}  // namespace scatterlab
