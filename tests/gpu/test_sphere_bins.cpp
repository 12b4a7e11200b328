/// The sphere bins built on the GPU (gpu::binSpheresGpu, issue 33) against the host's
/// (gpu::binSpheres): the same offsets and the same lists, each in ascending sphere order, from
/// spheres whose count the GPU reads from a buffer; and the overflow word when the caller's item
/// capacity is too small.

#include <algorithm>
#include <limits>
#include <random>

#include "gpu/records.h"
#include "gpu/shaders.h"
#include "gpu/sphere_bins.h"
#include "gpu_support.h"

namespace scatterlab::testing {
namespace {

const Box kBox{Vec3(-0.3f, 0.1f, 0.2f), Vec3(1.2f, 0.9f, 1.7f)};

/// `n` spheres (fixed seed) over kBox and around it: mostly a few voxels across, some large
/// (reaching many bins, a few every bin), centres up to half the box outside it, and some that
/// bin nowhere (radius 0 or negative, NaN centre or radius).
std::vector<glm::vec4> randomSpheres(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const Vec3 lo = kBox.min - 0.5f * kBox.extent(), size = 2.0f * kBox.extent();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<glm::vec4> spheres(n);
  for (glm::vec4& s : spheres) {
    const Vec3 c = lo + Vec3(u(rng), u(rng), u(rng)) * size;
    const float kind = u(rng);
    float r = 0.005f + 0.05f * u(rng);
    if (kind < 0.10f)
      r = 0.3f + 1.2f * u(rng);  // many bins, or all of them
    else if (kind < 0.13f)
      r = 0.0f;
    else if (kind < 0.14f)
      r = -0.1f;
    else if (kind < 0.15f)
      r = nan;
    s = glm::vec4(c, r);
    if (kind >= 0.15f && kind < 0.16f) s.y = nan;
  }
  return spheres;
}

struct GpuListing {
  std::vector<GLuint> offsets, items;
  GLuint overflow = 0;
  IVec3 bins{0};
};

/// binSpheresGpu of the first `count` of `spheres` (the buffer holds them all, the count sits in
/// a count buffer at slot 2 beside other words), read back.
GpuListing binOnGpu(const std::vector<glm::vec4>& spheres, std::size_t count, IVec3 dims,
                    std::size_t itemCapacity) {
  std::vector<gpu::GpuSamplePoint> packed;
  for (const glm::vec4& s : spheres) packed.push_back({Vec3(s), s.w});
  const gpu::Buffer points(packed.size() * sizeof(gpu::GpuSamplePoint), packed.data(), 0,
                           "test spheres");
  const GLuint words[4] = {7, 999999, GLuint(count), 5};
  const gpu::Buffer counts(sizeof words, words, 0, "test counts");
  gpu::ScanScratch scratch;
  gpu::resetLoopGuard();
  const gpu::GpuBins bins = gpu::binSpheresGpu(points, counts, 2, spheres.size(), kBox, dims,
                                               itemCapacity, scratch, "test bins");
  GpuListing out;
  out.bins = bins.bins;
  const std::size_t nBins = std::size_t(bins.bins.x) * bins.bins.y * bins.bins.z;
  out.offsets.resize(nBins + 1);
  bins.offsets.read(out.offsets.data(), out.offsets.size() * sizeof(GLuint));
  out.items.resize(std::min<std::size_t>(out.offsets.back(), itemCapacity));
  bins.items.read(out.items.data(), out.items.size() * sizeof(GLuint));
  out.overflow = bins.readOverflow();
  EXPECT_EQ(gpu::loopGuardCut(), "");  // no invocation cut short by llvmpipe's loop cap
  return out;
}

TEST(GpuSphereBins, EqualTheHostsBins) {
  SCATTERLAB_REQUIRE_GPU();
  const std::vector<glm::vec4> spheres = randomSpheres(3000, 33);
  const std::size_t count = 2400;  // the 600 past it must not be binned
  for (const IVec3 dims : {IVec3(37, 20, 51), IVec3(32, 32, 32)}) {
    SCOPED_TRACE("dims " + std::to_string(dims.x) + "x" + std::to_string(dims.y) + "x" +
                 std::to_string(dims.z));
    const gpu::SphereBins host =
        gpu::binSpheres(std::span<const glm::vec4>(spheres.data(), count), kBox, dims, "test bins");
    GLuint longest = 0;  // lists longer than a workgroup of the fill, to need sorting
    for (std::size_t b = 0; b + 1 < host.offsets.size(); ++b)
      longest = std::max(longest, host.offsets[b + 1] - host.offsets[b]);
    ASSERT_GT(longest, 100u);
    // The capacity exactly the total, and with room to spare.
    for (const std::size_t capacity : {host.items.size(), host.items.size() + 1000}) {
      const GpuListing gpu = binOnGpu(spheres, count, dims, capacity);
      EXPECT_EQ(gpu.bins, host.bins);
      EXPECT_EQ(gpu.overflow, 0u);
      EXPECT_EQ(gpu.offsets, host.offsets);
      EXPECT_EQ(gpu.items, host.items);
    }
  }
}

TEST(GpuSphereBins, SortsListsLongerThanSharedMemoryHolds) {
  SCATTERLAB_REQUIRE_GPU();
  // 2500 of 3000 spheres reaching every bin of a small grid: lists of 2500 and more (sorted in
  // the list itself, past the shader's 2048 entries of shared memory).
  std::vector<glm::vec4> spheres = randomSpheres(3000, 7);
  for (std::size_t j = 0; j < spheres.size(); ++j)
    if (j % 6 != 0) spheres[j] = glm::vec4(0.5f, 0.5f, 0.9f, 3.0f);
  const IVec3 dims(19, 9, 17);
  const gpu::SphereBins host = gpu::binSpheres(spheres, kBox, dims, "test bins");
  const GpuListing gpu = binOnGpu(spheres, spheres.size(), dims, host.items.size());
  EXPECT_EQ(gpu.overflow, 0u);
  EXPECT_EQ(gpu.offsets, host.offsets);
  EXPECT_EQ(gpu.items, host.items);
}

TEST(GpuSphereBins, TooSmallAnItemCapacityRecordsTheTotalAndCutsTheLists) {
  SCATTERLAB_REQUIRE_GPU();
  const std::vector<glm::vec4> spheres = randomSpheres(1000, 5);
  const IVec3 dims(37, 20, 51);
  const gpu::SphereBins host = gpu::binSpheres(spheres, kBox, dims, "test bins");
  const GLuint total = GLuint(host.items.size());
  for (const GLuint capacity : {total / 2, total - 1, 0u}) {
    SCOPED_TRACE(capacity);
    const GpuListing gpu = binOnGpu(spheres, spheres.size(), dims, capacity);
    EXPECT_EQ(gpu.overflow, total);
    // Every offset clamped to the capacity; the lists wholly below it are the host's.
    ASSERT_EQ(gpu.offsets.size(), host.offsets.size());
    for (std::size_t b = 0; b < host.offsets.size(); ++b)
      EXPECT_EQ(gpu.offsets[b], std::min(host.offsets[b], capacity)) << "bin " << b;
    for (std::size_t b = 0; b + 1 < host.offsets.size() && host.offsets[b + 1] <= capacity; ++b)
      for (GLuint k = host.offsets[b]; k < host.offsets[b + 1]; ++k)
        ASSERT_EQ(gpu.items[k], host.items[k]) << "bin " << b;
  }
}

TEST(GpuSphereBins, NoSpheresBinNothing) {
  SCATTERLAB_REQUIRE_GPU();
  const std::vector<glm::vec4> spheres = randomSpheres(100, 1);
  const GpuListing gpu = binOnGpu(spheres, 0, IVec3(37, 20, 51), 16);
  EXPECT_EQ(gpu.overflow, 0u);
  EXPECT_EQ(gpu.offsets, std::vector<GLuint>(gpu.offsets.size(), 0u));
}

}  // namespace
}  // namespace scatterlab::testing
