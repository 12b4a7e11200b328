#include "gpu/device_samples.h"

#include <algorithm>
#include <cmath>

#include "gpu/records.h"
#include "gpu/scan.h"

namespace scatterlab::gpu {

bool DeviceSamples::setPoints(std::span<const RadianceSample> samples) {
  std::vector<glm::vec4> now;
  now.reserve(samples.size());
  for (const RadianceSample& s : samples) now.emplace_back(s.position, s.radius);
  if (points && now == spheres && !onDevice) return false;
  onDevice.reset();
  spheres = std::move(now);
  std::vector<GpuSamplePoint> packed;
  packed.reserve(spheres.size());
  for (const glm::vec4& p : spheres) packed.push_back({Vec3(p), p.w});
  // The last set's buffers where they are large enough (a set that grows by a few samples
  // from frame to frame makes no buffer), else grown with headroom.
  ensure(points, packed.size() * sizeof(GpuSamplePoint), "sample positions", Growth::Varies);
  if (!packed.empty())
    glNamedBufferSubData(points.id(), 0, GLsizeiptr(packed.size() * sizeof(GpuSamplePoint)),
                         packed.data());
  ensure(radiance, spheres.size() * sizeof(GpuRadianceRecord), "sample S and grad S",
         Growth::Varies);
  radianceCurrent = false;
  binsCurrent_ = false;
  fill.reset();
  return true;
}

namespace {

/// The most bins one sphere of radius r can be listed in (binSpheres' range: the voxel centres
/// within r, one voxel of margin each side, and the rounding of floor and ceil, at most
/// 2r / cell + 4 voxels apart per axis), at most the grid's bins.
std::size_t binsPerSphere(float r, const Vec3& cell, IVec3 bins) {
  std::size_t n = 1;
  for (int a = 0; a < 3; ++a) {
    const double span = 2.0 * double(r) / double(cell[a]) + 4.0;
    const double perAxis = std::floor(span / kBinVoxels) + 2.0;
    n *= std::size_t(std::min(perAxis, double(bins[a])));
  }
  return n;
}

}  // namespace

void DeviceSamples::reserveOnDevice(std::size_t capacity,
                                    std::vector<std::pair<std::size_t, float>> radii) {
  spheres.clear();
  binsCurrent_ = false;
  if (deviceBins_) spareBins_ = std::move(*deviceBins_);  // their buffers serve the next bins
  deviceBins_.reset();
  fill.reset();
  radianceCurrent = false;
  if (!onDevice) onDevice.emplace();
  ensure(points, capacity * sizeof(GpuSamplePoint), "sample positions (on device)");
  ensure(radiance, capacity * sizeof(GpuRadianceRecord), "sample S and grad S (on device)");
  ensure(onDevice->count, sizeof(GLuint), "sample count (on device)");
  onDevice->capacity = capacity;
  onDevice->radii = std::move(radii);
}

NearestFill& DeviceSamples::fillFor(const Box& bounds, IVec3 dims, bool* created) {
  *created = !fill || fill->dims != dims || fill->bounds.min != bounds.min ||
             fill->bounds.max != bounds.max;
  if (*created) {
    fill.emplace();
    fill->bounds = bounds;
    fill->dims = dims;
    // At most every voxel, at most 4 M entries (32 MiB): past that the list overflows, and every
    // frame searches as without it.
    fill->capacity = std::min<std::size_t>(std::size_t(dims.x) * dims.y * dims.z, 1u << 22);
    fill->entries =
        Buffer(fill->capacity * 2 * sizeof(GLuint), nullptr, 0, "nearest-sample fill entries");
    const GLuint zeros[2] = {0, 0};
    fill->words = Buffer(sizeof zeros, zeros, 0, "nearest-sample fill count");
  }
  return *fill;
}

const BinBuffers& DeviceSamples::binsFor(const Box& bounds, IVec3 dims, IVec3* binCount,
                                         const char* pass) {
  if (onDevice) {
    // Binned on the GPU from the count the GPU holds (the samples change every frame). The
    // lists' room: each part of the list with the bins its spheres can reach.
    const Vec3 cell = bounds.extent() / Vec3(dims);
    const IVec3 nBins = (dims + IVec3(kBinVoxels - 1)) / kBinVoxels;
    std::size_t items = 0, most = 0;
    float largest = 0.0f;
    for (const auto& [count, radius] : onDevice->radii) {
      items += count * binsPerSphere(radius, cell, nBins);
      largest = std::max(largest, radius);
    }
    most = onDevice->capacity * binsPerSphere(largest, cell, nBins);
    binsCurrent_ = false;
    GpuBins previous = deviceBins_ ? std::move(*deviceBins_) : std::move(spareBins_);
    deviceBins_.reset();
    deviceBins_.emplace(binSpheresGpu(points, onDevice->count, 0, onDevice->capacity, bounds, dims,
                                      std::min(items, most), scratch_, pass, std::move(previous)));
    *binCount = deviceBins_->bins;
    return *deviceBins_;
  }
  if (!binsCurrent_ || binBounds_.min != bounds.min || binBounds_.max != bounds.max ||
      binDims_ != dims) {
    const SphereBins b = binSpheres(spheres, bounds, dims, pass);
    bins_.upload(b);  // into the buffers of the last sample set where they are large enough
    binsCurrent_ = true;
    binBounds_ = bounds;
    binDims_ = dims;
    binCount_ = b.bins;
  }
  *binCount = binCount_;
  return bins_;
}

}  // namespace scatterlab::gpu
