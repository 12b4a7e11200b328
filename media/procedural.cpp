#include "media/procedural.h"

#include <sstream>

#include "core/error.h"

namespace scatterlab {

void UniformDensity::build(DensityGrid& grid) const {
  std::fill(grid.data().begin(), grid.data().end(), value_);
}

std::string UniformDensity::describe() const {
  return "uniform density " + std::to_string(value_);
}

float GaussianDensity::eval(const Vec3& x) const {
  float d = 0.0f;
  for (const GaussianBlob& b : blobs_) {
    const Vec3 v = x - b.center;
    const float r2 = b.radius * b.radius, q = glm::dot(v, v);
    if (q < kCullRadius * kCullRadius * r2) d += b.weight * std::exp(-q / r2);
  }
  return d;
}

void GaussianDensity::build(DensityGrid& grid) const {
  // Splatting (paper Sec. 6, CPU variant): each blob touches only the voxels within 3r.
  // Serial over blobs keeps the sum order (and so the result) deterministic.
  std::fill(grid.data().begin(), grid.data().end(), 0.0f);
  const IVec3 n = grid.dims();
  const Vec3 cell = grid.cellSize(), lo = grid.bounds().min;
  for (const GaussianBlob& b : blobs_) {
    const float R = kCullRadius * b.radius, r2 = b.radius * b.radius;
    const IVec3 i0 = glm::max(IVec3(glm::ceil((b.center - R - lo) / cell - 0.5f)), IVec3(0));
    const IVec3 i1 = glm::min(IVec3(glm::floor((b.center + R - lo) / cell - 0.5f)), n - 1);
    for (int k = i0.z; k <= i1.z; ++k)
      for (int j = i0.y; j <= i1.y; ++j)
        for (int i = i0.x; i <= i1.x; ++i) {
          const Vec3 v = grid.cellCenter(i, j, k) - b.center;
          const float q = glm::dot(v, v);
          if (q < R * R) grid.at(i, j, k) += b.weight * std::exp(-q / r2);
        }
  }
}

std::string GaussianDensity::describe() const {
  return "sum of " + std::to_string(blobs_.size()) + " Gaussian blob(s)";
}

float HeightDensity::eval(const Vec3& x) const {
  const float t = std::clamp((x.y - box_.min.y) / (box_.max.y - box_.min.y), 0.0f, 1.0f);
  return bottom_ + (top_ - bottom_) * t;
}

std::string HeightDensity::describe() const {
  return "height gradient from " + std::to_string(bottom_) + " (bottom) to " +
         std::to_string(top_) + " (top)";
}

}  // namespace scatterlab
