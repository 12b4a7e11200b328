#include "gpu/device_samples.h"

#include <algorithm>

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
  points = Buffer();  // the old storage goes back to the recycler first
  points = Buffer(packed.size() * sizeof(GpuSamplePoint), packed.data(), 0, "sample positions");
  radiance = Buffer();
  radiance = Buffer(spheres.size() * sizeof(GpuRadianceRecord), nullptr, 0, "sample S and grad S");
  radianceCurrent = false;
  bins_.reset();
  return true;
}

void DeviceSamples::reserveOnDevice(std::size_t capacity, std::size_t binItems) {
  spheres.clear();
  bins_.reset();
  radianceCurrent = false;
  if (!onDevice) onDevice.emplace();
  ensure(points, capacity * sizeof(GpuSamplePoint), "sample positions (on device)");
  ensure(radiance, capacity * sizeof(GpuRadianceRecord), "sample S and grad S (on device)");
  ensure(onDevice->count, sizeof(GLuint), "sample count (on device)");
  onDevice->capacity = capacity;
  onDevice->binItems = binItems;
}

const BinBuffers& DeviceSamples::binsFor(const Box& bounds, IVec3 dims, IVec3* binCount,
                                         const char* pass) {
  if (onDevice) {
    // TEMPORARY (until the GPU builds the bins): the list read back and binned on the host.
    GLuint n = 0;
    onDevice->count.read(&n, sizeof n);
    std::vector<GpuSamplePoint> pts(n);
    if (n) points.read(pts.data(), n * sizeof(GpuSamplePoint));
    std::vector<glm::vec4> sph;
    for (const GpuSamplePoint& p : pts) sph.emplace_back(p.position, p.radius);
    bins_.reset();
    const SphereBins b = binSpheres(sph, bounds, dims, pass);
    bins_.emplace(b);
    *binCount = b.bins;
    return *bins_;
  }
  if (!bins_ || binBounds_.min != bounds.min || binBounds_.max != bounds.max || binDims_ != dims) {
    bins_.reset();
    const SphereBins b = binSpheres(spheres, bounds, dims, pass);
    bins_.emplace(b);
    binBounds_ = bounds;
    binDims_ = dims;
    binCount_ = b.bins;
  }
  *binCount = binCount_;
  return *bins_;
}

}  // namespace scatterlab::gpu
