#include "media/procedural.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <algorithm>

#include <sstream>

#include "core/error.h"

namespace scatterlab {

void UniformDensity::build(DensityGrid& grid) const {
  std::fill(grid.data().begin(), grid.data().end(), value_);
}

std::string UniformDensity::describe() const {
  return "uniform density " + std::to_string(value_);
}

float evalGaussians(std::span<const GaussianBlob> blobs, const Vec3& x) {
  float d = 0.0f;
  for (const GaussianBlob& b : blobs) {
    const Vec3 v = x - b.center;
    const float r2 = b.radius * b.radius, q = glm::dot(v, v);
    const float R = GaussianDensity::kCullRadius * b.radius;
    if (q < R * R) d += b.weight * std::exp(-q / r2);
  }
  return d;
}

void splatGaussians(std::span<const GaussianBlob> blobs, DensityGrid& grid) {
  const IVec3 n = grid.dims();
  const Vec3 cell = grid.cellSize(), lo = grid.bounds().min, nf(n);
  tbb::parallel_for(tbb::blocked_range<int>(0, n.z, 4), [&](const tbb::blocked_range<int>& r) {
    for (const GaussianBlob& b : blobs) {
      const float R = GaussianDensity::kCullRadius * b.radius, r2 = b.radius * b.radius;
      // One extra cell each side so float rounding never drops a cell; q < R² culls.
      IVec3 i0 = IVec3(glm::clamp(glm::floor((b.center - R - lo) / cell - 0.5f), Vec3(0), nf));
      IVec3 i1 =
          IVec3(glm::clamp(glm::ceil((b.center + R - lo) / cell - 0.5f), Vec3(-1), nf - 1.0f));
      i0.z = std::max(i0.z, r.begin());
      i1.z = std::min(i1.z, r.end() - 1);
      for (int k = i0.z; k <= i1.z; ++k)
        for (int j = i0.y; j <= i1.y; ++j)
          for (int i = i0.x; i <= i1.x; ++i) {
            const Vec3 v = grid.cellCenter(i, j, k) - b.center;
            const float q = glm::dot(v, v);
            if (q < R * R) grid.at(i, j, k) += b.weight * std::exp(-q / r2);
          }
    }
  });
}

float GaussianDensity::eval(const Vec3& x) const {
  return evalGaussians(blobs_, x);
}

void GaussianDensity::build(DensityGrid& grid) const {
  std::fill(grid.data().begin(), grid.data().end(), 0.0f);
  splatGaussians(blobs_, grid);
}

std::string GaussianDensity::describe() const {
  return "sum of " + std::to_string(blobs_.size()) + " Gaussian blob(s)";
}

std::optional<float> GaussianDensity::peak() const {
  // The sums at the centres: where a sum of Gaussians peaks unless blobs overlap closely (two
  // equal blobs one radius apart peak between them, 14 % higher). n² evaluations: not
  // estimated for more than kPeakBlobs blobs.
  constexpr std::size_t kPeakBlobs = 4096;
  if (blobs_.size() > kPeakBlobs) return std::nullopt;
  float m = 0.0f;
  for (const GaussianBlob& b : blobs_) m = std::max(m, evalGaussians(blobs_, b.center));
  return m;
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

namespace scatterlab {

namespace {
// Perlin's reference permutation (Improved Noise reference implementation, 2002).
constexpr int kPerlinPermutation[256] = {
    151, 160, 137, 91,  90,  15,  131, 13,  201, 95,  96,  53,  194, 233, 7,   225, 140, 36,  103,
    30,  69,  142, 8,   99,  37,  240, 21,  10,  23,  190, 6,   148, 247, 120, 234, 75,  0,   26,
    197, 62,  94,  252, 219, 203, 117, 35,  11,  32,  57,  177, 33,  88,  237, 149, 56,  87,  174,
    20,  125, 136, 171, 168, 68,  175, 74,  165, 71,  134, 139, 48,  27,  166, 77,  146, 158, 231,
    83,  111, 229, 122, 60,  211, 133, 230, 220, 105, 92,  41,  55,  46,  245, 40,  244, 102, 143,
    54,  65,  25,  63,  161, 1,   216, 80,  73,  209, 76,  132, 187, 208, 89,  18,  169, 200, 196,
    135, 130, 116, 188, 159, 86,  164, 100, 109, 198, 173, 186, 3,   64,  52,  217, 226, 250, 124,
    123, 5,   202, 38,  147, 118, 126, 255, 82,  85,  212, 207, 206, 59,  227, 47,  16,  58,  17,
    182, 189, 28,  42,  223, 183, 170, 213, 119, 248, 152, 2,   44,  154, 163, 70,  221, 153, 101,
    155, 167, 43,  172, 9,   129, 22,  39,  253, 19,  98,  108, 110, 79,  113, 224, 232, 178, 185,
    112, 104, 218, 246, 97,  228, 251, 34,  242, 193, 238, 210, 144, 12,  191, 179, 162, 241, 81,
    51,  145, 235, 249, 14,  239, 107, 49,  192, 214, 31,  181, 199, 106, 157, 184, 84,  204, 176,
    115, 121, 50,  45,  127, 4,   150, 254, 138, 236, 205, 93,  222, 114, 67,  29,  24,  72,  243,
    141, 128, 195, 78,  66,  215, 61,  156, 180};

double fade(double t) {
  return t * t * t * (t * (t * 6 - 15) + 10);
}
double lerp(double t, double a, double b) {
  return a + t * (b - a);
}
double grad(int hash, double x, double y, double z) {
  const int h = hash & 15;
  const double u = h < 8 ? x : y, v = h < 4 ? y : h == 12 || h == 14 ? x : z;
  return ((h & 1) == 0 ? u : -u) + ((h & 2) == 0 ? v : -v);
}
}  // namespace

PerlinNoise::PerlinNoise(std::uint32_t seed) {
  int perm[256];
  std::copy(std::begin(kPerlinPermutation), std::end(kPerlinPermutation), perm);
  if (seed != 0) {
    std::uint64_t s = 0x9E3779B97F4A7C15ull ^ seed;
    for (int i = 255; i > 0; --i) {
      s = s * 6364136223846793005ull + 1442695040888963407ull;
      const int j = int((s >> 33) % std::uint64_t(i + 1));
      std::swap(perm[i], perm[j]);
    }
  }
  for (int i = 0; i < 256; ++i) p_[i] = p_[i + 256] = perm[i];
}

double PerlinNoise::noise(double x, double y, double z) const {
  const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const int X = int(fx) & 255, Y = int(fy) & 255, Z = int(fz) & 255;
  x -= fx;
  y -= fy;
  z -= fz;
  const double u = fade(x), v = fade(y), w = fade(z);
  const int A = p_[X] + Y, AA = p_[A] + Z, AB = p_[A + 1] + Z, B = p_[X + 1] + Y, BA = p_[B] + Z,
            BB = p_[B + 1] + Z;
  return lerp(
      w,
      lerp(v, lerp(u, grad(p_[AA], x, y, z), grad(p_[BA], x - 1, y, z)),
           lerp(u, grad(p_[AB], x, y - 1, z), grad(p_[BB], x - 1, y - 1, z))),
      lerp(v, lerp(u, grad(p_[AA + 1], x, y, z - 1), grad(p_[BA + 1], x - 1, y, z - 1)),
           lerp(u, grad(p_[AB + 1], x, y - 1, z - 1), grad(p_[BB + 1], x - 1, y - 1, z - 1))));
}

double PerlinNoise::fbm(double x, double y, double z, int octaves) const {
  double sum = 0, amp = 1, norm = 0, f = 1;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * noise(x * f, y * f, z * f);
    norm += amp;
    amp *= 0.5;
    f *= 2;
  }
  return norm > 0 ? sum / norm : 0;
}

float DustyRoomDensity::eval(const Vec3& x) const {
  const float t = std::clamp((x.y - box_.min.y) / (box_.max.y - box_.min.y), 0.0f, 1.0f);
  const Vec3 q = p_.frequency * (x - box_.min - p_.wind * p_.time);
  const double n = p_.octaves > 0 ? noise_.fbm(q.x, q.y, q.z, p_.octaves) : 0.0;
  return std::max(0.0f, p_.floor + (p_.ceiling - p_.floor) * t + p_.amplitude * float(n));
}

std::string DustyRoomDensity::describe() const {
  std::ostringstream os;
  os << "dusty room: " << p_.floor << " (floor) to " << p_.ceiling << " (ceiling) + "
     << p_.amplitude << " x Perlin fBm (" << p_.octaves << " octaves, frequency " << p_.frequency
     << ", seed " << p_.seed << "), time " << p_.time;
  return os.str();
}

}  // namespace scatterlab
