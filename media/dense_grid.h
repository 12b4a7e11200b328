#pragma once
/// A dense float grid given in the scene (inline values or a raw float32 file), resampled
/// trilinearly (cell-centre convention) into the medium box.

#include "core/density_model.h"

namespace scatterlab {

class DenseGridDensity : public DensityModel {
 public:
  /// `grid` covers the medium box.
  explicit DenseGridDensity(DensityGrid grid, std::string source)
      : grid_(std::move(grid)), source_(std::move(source)) {}
  std::string type() const override { return "grid"; }
  float eval(const Vec3& x) const override { return grid_.sample(x); }
  std::optional<float> peak() const override;
  void build(DensityGrid& out) const override;
  std::string describe() const override;
  const DensityGrid& grid() const { return grid_; }

 private:
  DensityGrid grid_;
  std::string source_;
};

/// Reads nx·ny·nz little-endian float32 values (x fastest, then y, then z). Throws IoError
/// naming the file when it is missing, a directory, or of the wrong size.
std::vector<float> readRawFloats(const std::string& path, IVec3 dims);

}  // namespace scatterlab
