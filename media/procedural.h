#pragma once
/// Procedural density models: uniform, Gaussian blobs, height gradient.

#include <cstdint>
#include <span>
#include <vector>

#include "core/density_model.h"

namespace scatterlab {

/// D(x) = value everywhere in the box.
class UniformDensity : public DensityModel {
 public:
  explicit UniformDensity(float value) : value_(value) {}
  std::string type() const override { return "uniform"; }
  float eval(const Vec3&) const override { return value_; }
  std::optional<float> peak() const override { return value_; }
  void build(DensityGrid& grid) const override;
  std::string describe() const override;
  float value() const { return value_; }

 private:
  float value_;
};

/// Σ_j w_j exp(−|x − c_j|²/r_j²) over `blobs`, each culled beyond 3·r_j.
float evalGaussians(std::span<const GaussianBlob> blobs, const Vec3& x);

/// Density construction by splatting (paper Sec. 6, CPU): adds each blob's w·exp(−|x−c|²/r²)
/// to the cell centres of `grid` within its culling radius (3r). Parallel over z slabs; every
/// cell sums the same terms in the same order as evalGaussians(), so splatting equals
/// evaluation and the result is deterministic.
void splatGaussians(std::span<const GaussianBlob> blobs, DensityGrid& grid);

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
  std::optional<float> peak() const override;
  bool isSumOfGaussians() const override { return true; }

  static constexpr float kCullRadius = kGaussianCullRadius;  ///< in units of r

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
  std::optional<float> peak() const override { return std::max(bottom_, top_); }
  std::string describe() const override;

 private:
  float bottom_, top_;
  Box box_;
};

}  // namespace scatterlab

namespace scatterlab {

/// Ken Perlin's improved noise (SIGGRAPH 2002): gradient noise in [-1, 1] (practically within
/// about ±1), zero at integer lattice points. `seed` 0 uses Perlin's reference permutation;
/// other seeds shuffle it (Fisher–Yates driven by a 64-bit LCG, identical on every platform).
class PerlinNoise {
 public:
  explicit PerlinNoise(std::uint32_t seed = 0);
  double noise(double x, double y, double z) const;
  /// Fractal sum of `octaves` octaves (frequency ×2, amplitude ×½ each), normalised so the
  /// amplitudes add up to 1.
  double fbm(double x, double y, double z, int octaves) const;

 private:
  int p_[512];
};

/// The paper's dusty room (Sec. 7): density interpolated linearly from `floor` at the box's
/// min.y to `ceiling` at max.y, plus noise detail:
///   D(x, t) = max(0, lerp(floor, ceiling, (y − min.y)/(max.y − min.y))
///                    + amplitude · fbm(frequency · (x − min − wind · t)))
/// so the noise pattern drifts with velocity `wind` (world units per unit time) as `time` moves.
struct DustyRoomParams {
  float floor = 0.6f, ceiling = 0.3f;
  float amplitude = 0.15f;  ///< density units
  float frequency = 4.0f;   ///< noise cells per world unit
  int octaves = 3;
  std::uint32_t seed = 0;
  float time = 0.0f;
  Vec3 wind{0.1f, 0.0f, 0.05f};  ///< world units per unit time
};

class DustyRoomDensity : public DensityModel {
 public:
  DustyRoomDensity(const Box& box, const DustyRoomParams& p) : box_(box), p_(p), noise_(p.seed) {}
  std::string type() const override { return "dusty-room"; }
  float eval(const Vec3& x) const override;
  std::string describe() const override;

 private:
  Box box_;
  DustyRoomParams p_;
  PerlinNoise noise_;
};

}  // namespace scatterlab
