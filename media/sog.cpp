#include "media/sog.h"

#include <tbb/parallel_for.h>

#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/limits.h"

namespace scatterlab {

static_assert(std::endian::native == std::endian::little,
              ".sog I/O assumes a little-endian host (the format is little-endian)");

// ---------------------------------------------------------------- residual hash

ResidualHash::ResidualHash(const Box& bounds, IVec3 dims, int bits, float step)
    : bounds_(bounds), dims_(dims), bits_(bits), step_(step) {
  if (bits != 8 && bits != 16) throw ConfigError("residual quantisation must be 8 or 16 bits");
  keys_.assign(16, kEmpty);
  codes_.assign(16, 0);
  shift_ = 32 - 4;
}

void ResidualHash::grow() {
  std::vector<std::uint32_t> oldKeys;
  std::vector<std::int16_t> oldCodes;
  oldKeys.swap(keys_);
  oldCodes.swap(codes_);
  const std::size_t cap = std::max<std::size_t>(16, oldKeys.size() * 2);
  keys_.assign(cap, kEmpty);
  codes_.assign(cap, 0);
  shift_ = 32 - std::countr_zero(cap);
  count_ = 0;
  for (std::size_t s = 0; s < oldKeys.size(); ++s)
    if (oldKeys[s] != kEmpty) insert(oldKeys[s], oldCodes[s]);
}

void ResidualHash::insert(std::uint32_t key, std::int16_t code) {
  if (keys_.empty() || (count_ + 1) * 2 > keys_.size()) grow();  // load factor <= 1/2
  std::size_t s = slot(key);
  while (keys_[s] != kEmpty) {
    if (keys_[s] == key) {
      codes_[s] = code;
      return;
    }
    s = (s + 1) & (keys_.size() - 1);
  }
  keys_[s] = key;
  codes_[s] = code;
  ++count_;
}

std::int16_t ResidualHash::code(std::uint32_t key) const {
  if (count_ == 0) return 0;
  std::size_t s = slot(key);
  while (keys_[s] != kEmpty) {
    if (keys_[s] == key) return codes_[s];
    s = (s + 1) & (keys_.size() - 1);
  }
  return 0;
}

namespace {

/// Trilinear interpolation between cell centres at continuous index u (clamped), reading
/// lattice values through `get(i, j, k)`. Shared by eval (hash reads) and splat (dense reads)
/// so both compute the same number.
template <class Get>
float trilinear(IVec3 n, Vec3 u, const Get& get) {
  u = glm::clamp(u, Vec3(0.0f), Vec3(n - 1));
  const int i0 = std::min(int(u.x), n.x - 1), j0 = std::min(int(u.y), n.y - 1),
            k0 = std::min(int(u.z), n.z - 1);
  const int i1 = std::min(i0 + 1, n.x - 1), j1 = std::min(j0 + 1, n.y - 1),
            k1 = std::min(k0 + 1, n.z - 1);
  const float fx = u.x - float(i0), fy = u.y - float(j0), fz = u.z - float(k0);
  const float c00 = get(i0, j0, k0) + (get(i1, j0, k0) - get(i0, j0, k0)) * fx;
  const float c10 = get(i0, j1, k0) + (get(i1, j1, k0) - get(i0, j1, k0)) * fx;
  const float c01 = get(i0, j0, k1) + (get(i1, j0, k1) - get(i0, j0, k1)) * fx;
  const float c11 = get(i0, j1, k1) + (get(i1, j1, k1) - get(i0, j1, k1)) * fx;
  const float c0 = c00 + (c10 - c00) * fy;
  const float c1 = c01 + (c11 - c01) * fy;
  return c0 + (c1 - c0) * fz;
}

Vec3 latticeIndex(const Box& b, IVec3 n, const Vec3& p) {
  return (p - b.min) / (b.extent() / Vec3(n)) - 0.5f;
}

}  // namespace

float ResidualHash::sample(const Vec3& p) const {
  if (count_ == 0 || !bounds_.contains(p)) return 0.0f;
  return trilinear(dims_, latticeIndex(bounds_, dims_, p),
                   [&](int i, int j, int k) { return at(i, j, k); });
}

std::vector<std::pair<std::uint32_t, std::int16_t>> ResidualHash::entries() const {
  std::vector<std::pair<std::uint32_t, std::int16_t>> e;
  e.reserve(count_);
  for (std::size_t s = 0; s < keys_.size(); ++s)
    if (keys_[s] != kEmpty) e.emplace_back(keys_[s], codes_[s]);
  std::sort(e.begin(), e.end());
  return e;
}

std::vector<float> ResidualHash::decode() const {
  std::vector<float> d(std::size_t(dims_.x) * dims_.y * dims_.z, 0.0f);
  for (std::size_t s = 0; s < keys_.size(); ++s)
    if (keys_[s] != kEmpty) d[keys_[s]] = float(codes_[s]) * step_;
  return d;
}

// ---------------------------------------------------------------- model

float SogModel::evalGaussians(const Vec3& x) const {
  return scatterlab::evalGaussians(gaussians, x);
}

void SogModel::splat(DensityGrid& grid, bool withResidual) const {
  const IVec3 n = grid.dims();
  std::fill(grid.data().begin(), grid.data().end(), 0.0f);
  std::vector<float> dense;
  const bool useF = withResidual && residual.size() > 0;
  if (useF) dense = residual.decode();
  const IVec3 rn = residual.dims();
  splatGaussians(gaussians, grid);
  if (!withResidual) return;
  tbb::parallel_for(tbb::blocked_range<int>(0, n.z, 4), [&](const tbb::blocked_range<int>& r) {
    const auto get = [&](int i, int j, int k) {
      return dense[(std::size_t(k) * rn.y + j) * rn.x + i];
    };
    for (int k = r.begin(); k < r.end(); ++k)
      for (int j = 0; j < n.y; ++j)
        for (int i = 0; i < n.x; ++i) {
          float& d = grid.at(i, j, k);
          const Vec3 p = grid.cellCenter(i, j, k);
          float f = 0.0f;
          if (useF && residual.bounds().contains(p))
            f = trilinear(rn, latticeIndex(residual.bounds(), rn, p), get);
          d = std::max(0.0f, d + f);
        }
  });
}

// ---------------------------------------------------------------- .sog files

namespace {

constexpr char kMagic[8] = {'S', 'C', 'L', 'S', 'O', 'G', '\r', '\n'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 72;
constexpr std::size_t kGaussianBytes = 20;

std::uint64_t fnv1a(const char* p, std::size_t n) {
  std::uint64_t h = 14695981039346656037ull;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= std::uint8_t(p[i]);
    h *= 1099511628211ull;
  }
  return h;
}

template <class T>
void put(std::string& s, const T& v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <class T>
T get(const std::string& s, std::size_t& off) {
  T v;
  std::memcpy(&v, s.data() + off, sizeof(T));
  off += sizeof(T);
  return v;
}

}  // namespace

std::size_t SogModel::fileBytes() const {
  return kHeaderBytes + gaussians.size() * kGaussianBytes +
         residual.size() * (4 + std::size_t(residual.bits() / 8)) + 8;
}

void writeSog(const std::string& path, const SogModel& m) {
  checkWritablePath(path);
  std::string s;
  s.reserve(m.fileBytes());
  s.append(kMagic, 8);
  put(s, kVersion);
  put(s, std::uint32_t(0));  // flags
  const Box& b = m.residual.bounds();
  for (int a = 0; a < 3; ++a) put(s, b.min[a]);
  for (int a = 0; a < 3; ++a) put(s, b.max[a]);
  for (int a = 0; a < 3; ++a) put(s, std::uint32_t(m.residual.dims()[a]));
  put(s, std::uint32_t(m.gaussians.size()));
  put(s, std::uint32_t(m.residual.size()));
  put(s, std::uint32_t(m.residual.bits()));
  put(s, m.residual.step());
  put(s, m.threshold);
  for (const GaussianBlob& g : m.gaussians) {
    put(s, g.center.x);
    put(s, g.center.y);
    put(s, g.center.z);
    put(s, g.radius);
    put(s, g.weight);
  }
  const auto e = m.residual.entries();
  for (const auto& [k, c] : e) put(s, k);
  for (const auto& [k, c] : e) {
    if (m.residual.bits() == 8)
      put(s, std::int8_t(c));
    else
      put(s, c);
  }
  put(s, fnv1a(s.data(), s.size()));
  writeBytesAtomically(path, s);
}

SogModel readSog(const std::string& path) {
  checkReadableFile(path, ".sog model");
  const auto bad = [&](const std::string& why) -> IoError {
    return IoError("'" + path + "' is not a valid .sog model: " + why);
  };
  // Header first, then its sizes against the file's size: nothing is allocated from a number
  // the file states before the file is known to hold that many bytes.
  std::error_code ec;
  const std::uintmax_t fileSize = std::filesystem::file_size(path, ec);
  if (ec) throw IoError("cannot read '" + path + "': " + ec.message());
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot read '" + path + "'");
  std::string s(std::size_t(std::min<std::uintmax_t>(fileSize, kHeaderBytes)), '\0');
  in.read(s.data(), std::streamsize(s.size()));
  if (in.gcount() != std::streamsize(s.size())) throw IoError("cannot read '" + path + "'");
  if (s.size() < 8 || std::memcmp(s.data(), kMagic, 8) != 0)
    throw bad("no .sog signature at its start (a foreign file?)");
  if (fileSize < kHeaderBytes + 8)
    throw bad("truncated (" + std::to_string(fileSize) + " bytes, the header alone needs " +
              std::to_string(kHeaderBytes + 8) + ")");
  std::size_t off = 8;
  const auto version = get<std::uint32_t>(s, off);
  if (version != kVersion)
    throw bad("format version " + std::to_string(version) + "; this build reads version " +
              std::to_string(kVersion));
  const auto flags = get<std::uint32_t>(s, off);
  if (flags != 0) throw bad("unknown flags " + std::to_string(flags));
  Box b;
  for (int a = 0; a < 3; ++a) b.min[a] = get<float>(s, off);
  for (int a = 0; a < 3; ++a) b.max[a] = get<float>(s, off);
  IVec3 dims;
  std::int64_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    const auto d = get<std::uint32_t>(s, off);
    if (d < 1 || d > 4096) throw bad("lattice dimension " + std::to_string(d) + " out of range");
    dims[a] = int(d);
    cells *= d;
  }
  if (cells > kMaxGridVoxels) throw bad("lattice larger than 512^3 voxels");
  if (!b.valid() || !std::isfinite(b.min.x + b.min.y + b.min.z + b.max.x + b.max.y + b.max.z))
    throw bad("invalid lattice box");
  const auto nG = get<std::uint32_t>(s, off);
  const auto nE = get<std::uint32_t>(s, off);
  const auto bits = get<std::uint32_t>(s, off);
  const auto step = get<float>(s, off);
  const auto threshold = get<float>(s, off);
  if (bits != 8 && bits != 16) throw bad("quantisation of " + std::to_string(bits) + " bits");
  // The largest code times the step must stay finite in single precision.
  if (!(std::isfinite(step) && step >= 0 && double(step) * 32767.0 <= 3.4e38))
    throw bad("invalid residual step");
  if (std::int64_t(nE) > cells)
    throw bad(std::to_string(nE) + " residual entries on a lattice of " + std::to_string(cells) +
              " cells");
  const std::uint64_t expected =
      kHeaderBytes + std::uint64_t(nG) * kGaussianBytes + std::uint64_t(nE) * (4 + bits / 8) + 8;
  if (fileSize != expected)
    throw bad((fileSize < expected ? "truncated: " : "trailing bytes: ") +
              std::to_string(fileSize) + " bytes, the header announces " +
              std::to_string(expected));
  // The model in memory: Gaussians, and the hash at load factor <= 1/2 (capacity up to 4x).
  checkMemory(path,
              "the .sog model (" + std::to_string(nG) + " Gaussians, " + std::to_string(nE) +
                  " residual entries)",
              double(nG) * sizeof(GaussianBlob) + double(nE) * 4 * 6 + double(fileSize));
  s.resize(std::size_t(fileSize));
  in.read(s.data() + kHeaderBytes, std::streamsize(fileSize - kHeaderBytes));
  if (in.gcount() != std::streamsize(fileSize - kHeaderBytes))
    throw bad("truncated while reading (the file changed?)");
  std::uint64_t stored;
  std::memcpy(&stored, s.data() + s.size() - 8, 8);
  if (stored != fnv1a(s.data(), s.size() - 8)) throw bad("checksum mismatch (corrupt file)");
  SogModel m;
  m.threshold = threshold;
  m.gaussians.resize(nG);
  const double diag = glm::length(glm::dvec3(b.max) - glm::dvec3(b.min));
  for (auto& g : m.gaussians) {
    g.center.x = get<float>(s, off);
    g.center.y = get<float>(s, off);
    g.center.z = get<float>(s, off);
    g.radius = get<float>(s, off);
    g.weight = get<float>(s, off);
    if (!std::isfinite(g.center.x + g.center.y + g.center.z + g.weight) ||
        !(g.radius > 0 && std::isfinite(g.radius)))
      throw bad("invalid Gaussian (non-finite value or radius <= 0)");
    // As scene Gaussians (core/scene.cpp): within 1e6 box diagonals, and a sum of all weights
    // that stays finite in single precision.
    const glm::dvec3 c(g.center), mid = (glm::dvec3(b.min) + glm::dvec3(b.max)) * 0.5;
    if (!(glm::length(c - mid) <= 1e6 * diag && double(g.radius) <= 1e6 * diag))
      throw bad("a Gaussian's centre or radius is more than 1e6 box diagonals from the box");
    if (!(std::abs(double(g.weight)) * double(nG) <= 3.4e38))
      throw bad("a Gaussian weight of " + std::to_string(g.weight) +
                " (the sum of the weights would overflow single precision)");
  }
  m.residual = ResidualHash(b, dims, int(bits), step);
  const std::size_t keyOff = off, codeOff = off + std::size_t(nE) * 4;
  std::uint32_t prev = 0;
  for (std::uint32_t e = 0; e < nE; ++e) {
    std::size_t ko = keyOff + std::size_t(e) * 4;
    const auto key = get<std::uint32_t>(s, ko);
    if (std::int64_t(key) >= cells || (e > 0 && key <= prev))
      throw bad("residual keys out of range or not ascending");
    prev = key;
    std::int16_t code;
    if (bits == 8) {
      std::size_t co = codeOff + e;
      code = get<std::int8_t>(s, co);
    } else {
      std::size_t co = codeOff + std::size_t(e) * 2;
      code = get<std::int16_t>(s, co);
    }
    m.residual.insert(key, code);
  }
  return m;
}

std::string SogDensity::describe() const {
  std::ostringstream os;
  const IVec3 d = model_.residual.dims();
  os << "sum of " << model_.gaussians.size() << " Gaussians + residual hash of "
     << model_.residual.size() << " entries (" << model_.residual.bits() << "-bit) on a " << d.x
     << "x" << d.y << "x" << d.z << " lattice, from " << source_;
  return os.str();
}

}  // namespace scatterlab
