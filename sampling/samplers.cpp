#include "sampling/samplers.h"

#include <algorithm>
#include <cstdint>
#include <map>
#include <numeric>

#include "core/error.h"
#include "core/limits.h"

namespace scatterlab {

namespace {

IVec3 dimsForLongAxis(const Vec3& ext, int nLong) {
  const float h = std::max({ext.x, ext.y, ext.z}) / float(nLong);
  IVec3 d;
  for (int a = 0; a < 3; ++a) d[a] = std::max(1, int(std::ceil(ext[a] / h - 1e-4f)));
  return d;
}

/// The occupancy the cell samplers count, memoized per grid (its long axis's cell count): from
/// the frame (Frame::countOccupiedCells), or every cell without skip_empty.
class Occupancy {
 public:
  Occupancy(Frame& frame, const Vec3& ext, bool skipEmpty)
      : frame_(frame), ext_(ext), skipEmpty_(skipEmpty) {}
  /// The occupied cells of the grid with `nLong` cells along the longest axis.
  long long operator()(int nLong) {
    count({nLong});
    return known_.at(nLong);
  }
  bool has(int nLong) const { return known_.contains(nLong); }
  /// Counts the grids of `nLongs` not counted yet, together (one call of the frame).
  void count(const std::vector<int>& nLongs) {
    std::vector<int> todo;
    std::vector<IVec3> grids;
    for (const int n : nLongs)
      if (!known_.contains(n) && std::find(todo.begin(), todo.end(), n) == todo.end()) {
        todo.push_back(n);
        grids.push_back(dimsForLongAxis(ext_, n));
      }
    if (todo.empty()) return;
    std::vector<long long> counts(grids.size());
    if (skipEmpty_)
      counts = frame_.countOccupiedCells(grids);
    else
      for (std::size_t i = 0; i < grids.size(); ++i)
        counts[i] = (long long)grids[i].x * grids[i].y * grids[i].z;
    for (std::size_t i = 0; i < todo.size(); ++i) known_[todo[i]] = counts[i];
  }
  /// The occupied cells of `dims`, ascending.
  std::vector<int> list(IVec3 dims) const {
    if (skipEmpty_) return frame_.occupiedCellList(dims);
    std::vector<int> all(std::size_t(dims.x) * dims.y * dims.z);
    std::iota(all.begin(), all.end(), 0);
    return all;
  }

 private:
  Frame& frame_;
  Vec3 ext_;
  bool skipEmpty_;
  std::map<int, long long> known_;
};

/// A frame over a host density volume it does not own (the DensityGrid overloads: no copy).
class DensityView : public Frame {
 public:
  explicit DensityView(const DensityGrid& density) : density_(density) {}
  Backend backend() const override { return Backend::Cpu; }
  void buildDensity(const Scene&) override {
    throw std::logic_error("DensityView::buildDensity: the view's density is given");
  }
  const DensityGrid& hostDensity() override { return density_; }
  void report(RenderStats&) override {}

 private:
  const DensityGrid& density_;
};

/// The midpoints the bisection over [lo, hi] (smallest n with occ(n) >= count) may visit in its
/// next `depth` steps, whichever way each goes.
void bisectionMids(int lo, int hi, int depth, std::vector<int>& out) {
  if (depth == 0 || lo >= hi) return;
  const int mid = (lo + hi) / 2;
  out.push_back(mid);
  bisectionMids(lo, mid, depth - 1, out);
  bisectionMids(mid + 1, hi, depth - 1, out);
}

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Uniform float in [0, 1) from the top 24 bits.
float unitFloat(std::uint64_t bits) {
  return float(bits >> 40) * (1.0f / 16777216.0f);
}

class GaussianCentresSampler : public Sampler {
 public:
  GaussianCentresSampler(std::optional<long long> count, float scale)
      : count_(count), scale_(scale) {}
  bool readsDensity() const override { return false; }
  long long plannedCount(const Scene& scene) const override {
    const auto* blobs = scene.medium.density ? scene.medium.density->gaussians() : nullptr;
    const long long gaussians = blobs ? (long long)blobs->size() : 0;
    return count_ ? std::min(*count_, gaussians) : gaussians;
  }
  std::vector<RadianceSample> generate(const Scene& scene, const DensityGrid&) override {
    const std::vector<GaussianBlob>* blobs = scene.medium.density->gaussians();
    if (!blobs) throw ConfigError("sampler 'gaussian-centres' needs a sum-of-Gaussians medium");
    std::vector<std::size_t> keep(blobs->size());
    std::iota(keep.begin(), keep.end(), std::size_t(0));
    if (count_ && std::size_t(*count_) < keep.size()) {
      const auto mass = [&](std::size_t i) {
        const GaussianBlob& b = (*blobs)[i];
        return double(b.weight) * b.radius * b.radius * b.radius;
      };
      std::stable_sort(keep.begin(), keep.end(),
                       [&](std::size_t a, std::size_t b) { return mass(a) > mass(b); });
      keep.resize(std::size_t(*count_));
      std::sort(keep.begin(), keep.end());
    }
    std::vector<RadianceSample> out;
    out.reserve(keep.size());
    for (std::size_t i : keep) {
      const GaussianBlob& b = (*blobs)[i];
      RadianceSample s;
      s.position = b.center;
      s.radius = scale_ * b.radius;
      s.weight = b.weight;
      out.push_back(s);
    }
    return out;
  }

 private:
  std::optional<long long> count_;
  float scale_;
};

class CellSampler : public Sampler {
 public:
  CellSampler(bool jitter, long long count, float scale, std::uint64_t seed, bool skipEmpty,
              bool atMost)
      : jitter_(jitter),
        count_(count),
        scale_(scale),
        seed_(seed),
        skipEmpty_(skipEmpty),
        atMost_(atMost) {}
  /// The cells chosen come as close to `count` as the grid allows, or with at_most the most
  /// that do not exceed it (chooseSampleCells).
  long long plannedCount(const Scene&) const override { return count_; }
  /// Only the occupancy is read (Frame::occupiedCells): a GPU frame reads no density back.
  bool readsDensity() const override { return false; }
  std::vector<RadianceSample> generate(const Scene& scene, const DensityGrid& density) override {
    DensityView frame(density);
    return generate(frame, scene);
  }
  std::vector<RadianceSample> generate(Frame& frame, const Scene& scene) override {
    const Box& box = scene.medium.bounds;
    const SampleCells cells = chooseSampleCells(frame, box.extent(), scene.medium.resolution,
                                                count_, skipEmpty_, atMost_);
    const float R = scale_ * std::max({cells.cell.x, cells.cell.y, cells.cell.z});
    const Vec3 lo = box.min;
    std::vector<RadianceSample> out(cells.occupied.size());
    for (std::size_t n = 0; n < out.size(); ++n) {
      const int c = cells.occupied[n];
      const IVec3 ijk(c % cells.dims.x, (c / cells.dims.x) % cells.dims.y,
                      c / (cells.dims.x * cells.dims.y));
      Vec3 f(0.5f);
      if (jitter_) {
        std::uint64_t h = splitmix64(seed_ ^ splitmix64(std::uint64_t(c)));
        for (int a = 0; a < 3; ++a) {
          f[a] = unitFloat(h);
          h = splitmix64(h);
        }
      }
      out[n].position = lo + (Vec3(ijk) + f) * cells.cell;
      out[n].radius = R;
    }
    return out;
  }

 private:
  bool jitter_;
  long long count_;
  float scale_;
  std::uint64_t seed_;
  bool skipEmpty_;
  bool atMost_;
};

const Interval kCount = Interval::closed(1, 1e8);
/// `count` of the grid and jittered samplers when none is given.
constexpr long long kDefaultCount = 512;

/// `count` samples (and the cells they come from) must fit the memory limit.
void checkSampleMemory(Params& p, long long count) {
  checkMemory(p.keyPath("count"), std::to_string(count) + " radiance samples",
              sampleSetBytes(double(count)));
}

}  // namespace

const std::vector<KeyDoc>& samplerKeys() {
  static const std::vector<KeyDoc> keys = {
      {"type", "string",
       "gradient: jittered with count 8000, at_most (adaptive's budget cap); adaptive: grid with "
       "count 2000; with paper and for "
       "rbf, nearest: gaussian-centres when the medium is a sum of Gaussians, else jittered",
       "gaussian-centres, jittered, grid", "how the initial samples are placed", R"("jittered")"},
      {"count", "int", "512 (gaussian-centres: every Gaussian)", "1…1e8",
       "number of samples (gaussian-centres: keep the count Gaussians of largest mass)", "8"},
      {"radius_scale", "number", "3 (gaussian-centres), 1.75 (jittered), 1 (grid)", "> 0",
       "valid radius R_j in Gaussian radii or cell sizes", "1.5"},
      {"seed", "int", "0", "≥ 0", "jittered: random seed", "1"},
      {"skip_empty", "bool", "true", "true, false", "jittered, grid: drop cells without density",
       "false"},
      {"at_most", "bool", "false (true in gradient's default sampler)", "true, false",
       "jittered, grid: count is a ceiling (the finest cell grid with at most count occupied "
       "cells) instead of a target (the grid whose occupied cells come nearest to it)",
       "true"},
  };
  return keys;
}

double sampleSetBytes(double count) {
  return count * double(sizeof(RadianceSample) + 2 * sizeof(std::int64_t));
}

SampleCells chooseSampleCells(Frame& frame, const Vec3& ext, IVec3 nd, long long count,
                              bool skipEmpty, bool atMost) {
  // Cells no smaller than a voxel: below that, occupancy by voxel centres is meaningless.
  const int maxLong = std::max({nd.x, nd.y, nd.z});
  Occupancy occ(frame, ext, skipEmpty);
  // A frame that counts grids together (a GPU frame: one pass and one 4-byte-per-grid wait for
  // all) is asked ahead for every grid the next kAhead bisection steps may visit: the same
  // search and the same grid as one count per step, in 2 waits instead of 8 at 128³.
  const int ahead = frame.countsGridsTogether() && skipEmpty ? 4 : 0;
  const auto prefetch = [&](int lo, int hi, std::vector<int> also) {
    if (ahead == 0) return;
    bisectionMids(lo, hi, ahead, also);
    occ.count(also);
  };
  int lo = 1, hi = maxLong;  // smallest nLong with occ >= count, by bisection
  prefetch(lo, hi, {hi, hi - 1});
  if (occ(hi) < count) {
    lo = hi;
  } else {
    while (lo < hi) {
      const int mid = (lo + hi) / 2;
      if (!occ.has(mid)) prefetch(lo, hi, {});
      if (occ(mid) >= count)
        hi = mid;
      else
        lo = mid + 1;
    }
  }
  int best = lo;
  if (atMost) {
    while (best > 1 && occ(best) > count) --best;  // a ceiling (one cell if nothing fits)
  } else if (lo > 1 && std::llabs(occ(lo - 1) - count) < std::llabs(occ(lo) - count)) {
    best = lo - 1;
  }
  SampleCells c;
  c.dims = dimsForLongAxis(ext, best);
  c.cell = ext / Vec3(c.dims);
  c.occupied = occ.list(c.dims);
  return c;
}

SampleCells chooseSampleCells(const DensityGrid& density, long long count, bool skipEmpty,
                              bool atMost) {
  DensityView frame(density);
  return chooseSampleCells(frame, density.bounds().extent(), density.dims(), count, skipEmpty,
                           atMost);
}

void registerSamplers() {
  samplers().add("gaussian-centres", [](Params& p, const Scene& scene) {
    std::optional<long long> count;
    if (p.has("count")) {
      count = p.integer("count", std::nullopt, kCount);
      checkSampleMemory(p, *count);
    } else
      p.allow("count");
    const float scale = p.real("radius_scale", 3.0, Interval::above(0));
    if (!scene.medium.density || !scene.medium.density->gaussians())
      p.fail("type",
             "'gaussian-centres' needs a sum-of-Gaussians medium (one whose model "
             "exposes Gaussians, e.g. medium.density.type 'gaussians'), got '" +
                 (scene.medium.density ? scene.medium.density->type() : "none") + "'");
    return std::unique_ptr<Sampler>(new GaussianCentresSampler(count, scale));
  });
  const auto cell = [](bool jitter) {
    return [jitter](Params& p, const Scene&) {
      const long long count = p.integer("count", kDefaultCount, kCount);
      checkSampleMemory(p, count);
      const float scale = p.real("radius_scale", jitter ? 1.75 : 1.0, Interval::above(0));
      const std::uint64_t seed =
          jitter ? std::uint64_t(p.integer("seed", 0, Interval::atLeast(0))) : 0;
      const bool skipEmpty = p.boolean("skip_empty", true);
      const bool atMost = p.boolean("at_most", false);
      return std::unique_ptr<Sampler>(
          new CellSampler(jitter, count, scale, seed, skipEmpty, atMost));
    };
  };
  samplers().add("jittered", cell(true));
  samplers().add("grid", cell(false));
}

}  // namespace scatterlab
