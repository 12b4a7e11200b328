#pragma once
/// The paper's density representation (Eq. 3, after Zhou et al. 2007): a weighted sum of
/// Gaussians plus a residual field F kept in a spatial hash only where it matters,
///     D(x) = max(0, D̃(x) + F(x)),   D̃(x) = Σ_j w_j exp(−|x − c_j|²/r_j²)  (culled at 3 r_j).
/// F lives on the lattice of the grid the model was fitted to (cell centres, as DensityGrid)
/// and is interpolated trilinearly; lattice cells not in the hash hold F = 0. The clamp at 0
/// only removes small negative undershoots where the hash dropped a residual below threshold.

#include <cstdint>
#include <string>
#include <vector>

#include "core/density_model.h"
#include "media/procedural.h"  // GaussianBlob

namespace scatterlab {

/// Residual values on a lattice, stored sparsely: open addressing (linear probing) keyed by
/// the lattice cell's linear index, values quantised to signed integers times `step`.
class ResidualHash {
 public:
  ResidualHash() = default;
  /// Empty hash over the lattice `bounds`/`dims` (cell-centred, x fastest).
  ResidualHash(const Box& bounds, IVec3 dims, int bits, float step);

  /// Adds cell `key` (linear index) with quantised value `code` (non-zero). Keys must be new.
  void insert(std::uint32_t key, std::int16_t code);
  /// Quantised code of `key`, 0 when absent.
  std::int16_t code(std::uint32_t key) const;
  /// F at lattice cell (i, j, k): code · step.
  float at(int i, int j, int k) const {
    return float(code(std::uint32_t((std::int64_t(k) * dims_.y + j) * dims_.x + i))) * step_;
  }
  /// F at world point p: trilinear between cell centres, clamped to the outermost centres,
  /// 0 outside the lattice box or when the hash is empty.
  float sample(const Vec3& p) const;

  /// Entries sorted by key (for writing and tests).
  std::vector<std::pair<std::uint32_t, std::int16_t>> entries() const;
  /// Dense copy of F on its lattice (zeros where absent).
  std::vector<float> decode() const;

  std::size_t size() const { return count_; }
  const Box& bounds() const { return bounds_; }
  IVec3 dims() const { return dims_; }
  int bits() const { return bits_; }
  float step() const { return step_; }
  /// Memory of the table in bytes (keys and codes, empty slots included).
  std::size_t memoryBytes() const {
    return keys_.size() * (sizeof(std::uint32_t) + sizeof(std::int16_t));
  }

 private:
  static constexpr std::uint32_t kEmpty = 0xFFFFFFFFu;
  std::size_t slot(std::uint32_t key) const {
    return std::size_t((key * 2654435761u) >> shift_) & (keys_.size() - 1);
  }
  void grow();

  Box bounds_;
  IVec3 dims_{1};
  int bits_ = 8;
  float step_ = 0.0f;
  int shift_ = 0;
  std::size_t count_ = 0;
  std::vector<std::uint32_t> keys_;
  std::vector<std::int16_t> codes_;
};

/// A fitted model: Gaussians and the residual hash (which also defines the lattice).
struct SogModel {
  std::vector<GaussianBlob> gaussians;
  ResidualHash residual;
  float threshold = 0.0f;  ///< absolute |F| below which residuals were dropped (informative)

  /// D̃(x): the Gaussians alone, each culled at 3 r.
  float evalGaussians(const Vec3& x) const;
  /// D(x) = max(0, D̃(x) + F(x)).
  float eval(const Vec3& x) const { return std::max(0.0f, evalGaussians(x) + residual.sample(x)); }
  /// Density construction by splatting (paper Sec. 6, CPU): each Gaussian adds its weight to
  /// the cells within 3 r, then the residual is added and the sum clamped at 0. Equals eval()
  /// at every cell centre (same terms, same order). Parallel over z slabs (TBB).
  /// `withResidual` false gives D̃ alone (no clamp).
  void splat(DensityGrid& grid, bool withResidual = true) const;
  /// Bytes this model takes in a .sog file.
  std::size_t fileBytes() const;
};

/// Writes the versioned .sog binary format (docs/media.md), atomically (no partial file).
void writeSog(const std::string& path, const SogModel& model);
/// Reads and validates a .sog file. A missing, truncated, corrupt (checksum) or foreign file
/// or an unsupported version is an IoError naming the file; never a crash.
SogModel readSog(const std::string& path);

/// Density type "sog": one .sog file, or a sequence of frames chosen by time.
class SogDensity : public DensityModel {
 public:
  SogDensity(SogModel model, std::string source)
      : model_(std::move(model)), source_(std::move(source)) {}
  std::string type() const override { return "sog"; }
  float eval(const Vec3& x) const override { return model_.eval(x); }
  /// Splatting (SogModel::splat).
  void build(DensityGrid& grid) const override { model_.splat(grid); }
  /// The lattice box of the fitted grid.
  std::optional<Box> naturalBounds() const override { return model_.residual.bounds(); }
  /// The fitted Gaussians: the paper's initial radiance samples (gaussian-centres sampler).
  const std::vector<GaussianBlob>* gaussians() const override { return &model_.gaussians; }
  std::string describe() const override;
  const SogModel& model() const { return model_; }

 private:
  SogModel model_;
  std::string source_;
};

}  // namespace scatterlab
