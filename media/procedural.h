#pragma once
/// Procedural density models: uniform, Gaussian blobs, height gradient.

#include <vector>

#include "core/density_model.h"

namespace scatterlab {

/// D(x) = value everywhere in the box.
class UniformDensity : public DensityModel {
 public:
  explicit UniformDensity(float value) : value_(value) {}
  std::string type() const override { return "uniform"; }
  float eval(const Vec3&) const override { return value_; }
  void build(DensityGrid& grid) const override;
  std::string describe() const override;
  float value() const { return value_; }

 private:
  float value_;
};

/// D(x) = Σ w_j exp(−|x − c_j|²/r_j²), each blob culled beyond 3·r_j (the paper's culling
/// radius: the dropped tail is below w·e⁻⁹ ≈ 1.2e-4·w).
class GaussianDensity : public DensityModel {
 public:
  explicit GaussianDensity(std::vector<GaussianBlob> blobs) : blobs_(std::move(blobs)) {}
  std::string type() const override { return "gaussians"; }
  float eval(const Vec3& x) const override;
  /// Splats each blob into the voxels within its culling radius.
  void build(DensityGrid& grid) const override;
  std::string describe() const override;
  const std::vector<GaussianBlob>& blobs() const { return blobs_; }
  const std::vector<GaussianBlob>* gaussians() const override { return &blobs_; }

  static constexpr float kCullRadius = 3.0f;  ///< in units of r

 private:
  std::vector<GaussianBlob> blobs_;
};

/// Density varying linearly along +Y across the medium box, from `bottom` at min.y to `top`
/// at max.y (the paper's dusty room: 0.6 at the floor, 0.3 at the ceiling).
class HeightDensity : public DensityModel {
 public:
  HeightDensity(const Box& box, float bottom, float top) : bottom_(bottom), top_(top), box_(box) {}
  std::string type() const override { return "height"; }
  float eval(const Vec3& x) const override;
  std::string describe() const override;

 private:
  float bottom_, top_;
  Box box_;
};

}  // namespace scatterlab
