#include "cpu/interpolation.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <limits>

#include "cpu/gather_rows.h"
#include "cpu/per_voxel.h"
#include "shading/transport.h"

// The RBF baseline. Zhou, Ren, Lin, Bao, Guo, Shum, "Real-time smoke rendering using
// compensated ray marching" (2007; the paper's [Zhou et al. 2007b]) represent the density as
// D̃(x) = Σ_l w_l·B_l(x), B_l(x) = exp(−‖x − c_l‖²/r_l²) (the same Gaussians as the paper's
// Eq. 3), compute the source radiance J_l only at the RBF centres c_l, and interpolate it
// everywhere with the density RBFs themselves:
//     J(x) = Σ_l w_l·B_l(x)·J_l / Σ_l w_l·B_l(x)   ( = Σ_l w_l·B_l(x)·J_l / D̃(x) ),
// so that the low-frequency in-scatter term D̃(x)·J(x) = Σ_l w_l·B_l(x)·J_l is a sum of RBFs,
// each culled beyond its radius 3·r_l. That is what Interpolation::Rbf computes, with
// w_l = RadianceSample::weight and r_l = R_l/3: for gaussian-centres samples (R_l = 3·r_l,
// weight = w_l) it is exactly the formula above; for jittered or grid samples (the "dense
// RBF" of Fig. 3, which has no fitted Gaussians behind it) every w_l is 1 and r_l = R_l/3.
// Caveat: the formula is written from our reading of that paper (its text is not in this
// repository); Ren et al. only call it "the RBF-based interpolation described in
// [Zhou et al. 2007b]", and this normalised density-weighted form is the one consistent with
// splatting RBFs and with J being defined only at RBF centres.

namespace scatterlab {

namespace {

/// Nearest sample to a point, on a uniform grid of bins over the samples' bounding box.
class NearestIndex {
 public:
  explicit NearestIndex(std::span<const RadianceSample> s) : s_(s) {
    if (s.empty()) return;
    lo_ = hi_ = s[0].position;
    for (const auto& x : s) {
      lo_ = glm::min(lo_, x.position);
      hi_ = glm::max(hi_, x.position);
    }
    const float ext = std::max({hi_.x - lo_.x, hi_.y - lo_.y, hi_.z - lo_.z, 1e-20f});
    const int per = std::clamp(int(std::cbrt(double(s.size()) / 2.0)), 1, 64);
    cell_ = std::max(ext / float(per), 1e-20f);
    for (int a = 0; a < 3; ++a) n_[a] = std::clamp(int((hi_[a] - lo_[a]) / cell_) + 1, 1, 64);
    bins_.resize(std::size_t(n_.x) * n_.y * n_.z);
    for (std::size_t j = 0; j < s.size(); ++j) bins_[bin(cellOf(s[j].position))].push_back(int(j));
  }

  /// Index of the nearest sample (lowest index on ties); -1 when there are none.
  int nearest(const Vec3& p) const {
    if (s_.empty()) return -1;
    const IVec3 c0 = cellOf(p);
    int best = -1;
    float bestD2 = kInfinity;
    const int maxR = std::max({n_.x, n_.y, n_.z});
    for (int r = 0; r <= maxR; ++r) {
      for (int k = c0.z - r; k <= c0.z + r; ++k)
        for (int j = c0.y - r; j <= c0.y + r; ++j)
          for (int i = c0.x - r; i <= c0.x + r; ++i) {
            if (std::max({std::abs(i - c0.x), std::abs(j - c0.y), std::abs(k - c0.z)}) != r)
              continue;
            if (i < 0 || j < 0 || k < 0 || i >= n_.x || j >= n_.y || k >= n_.z) continue;
            for (int idx : bins_[bin({i, j, k})]) {
              const Vec3 d = p - s_[idx].position;
              const float d2 = glm::dot(d, d);
              if (d2 < bestD2 || (d2 == bestD2 && idx < best)) {
                bestD2 = d2;
                best = idx;
              }
            }
          }
      // Cells not yet visited are at least r cell widths away.
      const float bound = float(r) * cell_;
      if (best >= 0 && bestD2 <= bound * bound) break;
    }
    return best;
  }

 private:
  IVec3 cellOf(const Vec3& p) const {
    IVec3 c;
    for (int a = 0; a < 3; ++a)
      c[a] = int(std::clamp((p[a] - lo_[a]) / cell_, 0.0f, float(n_[a] - 1)));
    return c;
  }
  std::size_t bin(IVec3 c) const { return (std::size_t(c.z) * n_.y + c.y) * n_.x + c.x; }

  std::span<const RadianceSample> s_;
  Vec3 lo_{0.0f}, hi_{0.0f};
  float cell_ = 1.0f;
  IVec3 n_{1};
  std::vector<std::vector<int>> bins_;
};

bool usable(const RadianceSample& s) {
  return s.radius > 0.0f && std::isfinite(s.radius) && std::isfinite(s.position.x) &&
         std::isfinite(s.position.y) && std::isfinite(s.position.z);
}

/// Voxel index range [first, last] whose centres may lie within `r` of coordinate `p` along
/// one axis, widened by one voxel (the exact test is done per voxel), clamped to [0, n).
/// `invH` = 1/h. Floor and ceiling by conversion (the values are clamped to [−2, n + 1]): no
/// libm call, which made this 14 % of the gather in perf.
inline void voxelRange(float p, float r, float lo, float invH, int n, int& first, int& last) {
  const float a = std::clamp((p - r - lo) * invH - 0.5f, -2.0f, float(n) + 1.0f);
  const float b = std::clamp((p + r - lo) * invH - 0.5f, -2.0f, float(n) + 1.0f);
  const int ia = int(a), ib = int(b);  // truncation towards zero
  first = std::max(0, ia - (float(ia) > a) - 1);
  last = std::min(n - 1, ib + (float(ib) < b) + 1);
}

Vec3 clampNonNegative(Vec3 v) {
  return glm::max(v, Vec3(0.0f));
}

/// One slice's accumulators (structure of arrays, nx·ny each) and, per row, the span of voxels
/// some sphere touched ([max int, -1] when none). Kept per thread across slices.
struct SliceAccumulators {
  SliceAccumulators(std::size_t nxy, std::size_t ny, std::size_t nx, float emptyDen)
      : r(nxy, 0.0f),
        g(nxy, 0.0f),
        b(nxy, 0.0f),
        w(nxy, emptyDen),
        occ(nx, 0.0f),
        qr(nx, 0.0f),
        qg(nx, 0.0f),
        qb(nx, 0.0f),
        spanLo(ny, std::numeric_limits<int>::max()),
        spanHi(ny, -1) {}
  std::vector<float> r, g, b, w, occ;
  std::vector<float> qr, qg, qb;  ///< one row's normalised values
  std::vector<int> spanLo, spanHi;
  std::vector<char> lit;  ///< one row's LitReach test (with Gather::lit)
};

/// VoxelOccupancy (cpu/per_voxel.h), asked only of voxels no sphere covers. When the two
/// volumes share their layout (the default) it reads only the 3×3×3 density neighbourhood of
/// the voxels asked, and none outside the span of the neighbouring density rows' non-zero
/// voxels (found once, one pass over the density); otherwise it is occupancyMask.
class UncoveredOccupancy {
 public:
  UncoveredOccupancy(const DensityGrid& density, const RadianceGrid& out)
      : d_(density), n_(out.dims()) {
    same_ = n_ == density.dims() && out.bounds().min == density.bounds().min &&
            out.bounds().max == density.bounds().max;
    if (!same_) {
      mask_ = occupancyMask(density, out);
      return;
    }
    const std::size_t rows = std::size_t(n_.y) * n_.z;
    first_.assign(rows, n_.x);
    last_.assign(rows, -1);
    tbb::parallel_for(0, n_.z, [&](int k) {
      for (int j = 0; j < n_.y; ++j) {
        const std::size_t r = std::size_t(k) * n_.y + j;
        const float* row = &d_.at(0, j, k);
        int f = 0;
        while (f < n_.x && !(row[f] > 0.0f)) ++f;
        if (f == n_.x) continue;
        int l = n_.x - 1;
        while (!(row[l] > 0.0f)) --l;
        first_[r] = f;
        last_[r] = l;
      }
    });
  }

  /// [a, b]: no voxel of row (j, k) outside it is occupied (a > b: none is).
  void rowRange(int j, int k, int& a, int& b) const {
    if (!same_) {
      a = 0;
      b = n_.x - 1;
      return;
    }
    int f = n_.x, l = -1;
    for (int kk = std::max(k - 1, 0); kk <= std::min(k + 1, n_.z - 1); ++kk)
      for (int jj = std::max(j - 1, 0); jj <= std::min(j + 1, n_.y - 1); ++jj) {
        const std::size_t r = std::size_t(kk) * n_.y + jj;
        f = std::min(f, first_[r]);
        l = std::max(l, last_[r]);
      }
    a = std::max(f - 1, 0);
    b = std::min(l + 1, n_.x - 1);
  }

  bool operator()(int i, int j, int k) const {
    if (!same_) return mask_[(std::size_t(k) * n_.y + j) * n_.x + i] != 0;
    for (int kk = std::max(k - 1, 0); kk <= std::min(k + 1, n_.z - 1); ++kk)
      for (int jj = std::max(j - 1, 0); jj <= std::min(j + 1, n_.y - 1); ++jj) {
        const float* row = &d_.at(0, jj, kk);
        for (int ii = std::max(i - 1, 0); ii <= std::min(i + 1, n_.x - 1); ++ii)
          if (row[ii] > 0.0f) return true;
      }
    return false;
  }

 private:
  const DensityGrid& d_;
  IVec3 n_;
  bool same_ = false;
  std::vector<char> mask_;
  std::vector<int> first_, last_;
};

/// What every slice of one interpolateSamples call reads.
struct Gather {
  Interpolation kind;
  const DensityGrid& density;
  std::span<const RadianceSample> samples;
  RadianceGrid& out;
  Grid3<float>* weightSum;
  bool log;               ///< ValueSpace::Log
  float occlusionSigmaT;  ///< > 0: occlusion-aware gradient weights
  std::optional<TaylorBounds> bounds;
  IVec3 n;
  Vec3 h, lo, invH;    ///< out's voxel size, box minimum, 1 / voxel size
  float emptyDen;      ///< the weight sum of a voxel no sample reached
  float densityVoxel;  ///< smallest density voxel edge: the occlusion march's step bound
  const NearestIndex& nearest;
  const UncoveredOccupancy& occupied;
  /// With the factored volume where only spot lights shine (null otherwise): voxels it does
  /// not reach within `reach` are 0, and samples it does not reach within R + `reach` are left
  /// out (they cannot touch a voxel it reaches).
  const LitReach* lit;
  float reach;
};

/// Samples per Z slice, in sample order (binned once; each slice is one task and owns its
/// output slice, so threads never write the same voxel).
std::vector<std::vector<int>> binBySlice(const Gather& g) {
  std::vector<std::vector<int>> slices(std::size_t(g.n.z));
  for (std::size_t j = 0; j < g.samples.size(); ++j) {
    const RadianceSample& s = g.samples[j];
    if (!usable(s)) continue;
    if (g.lit && !g.lit->reaches(s.position, s.radius + g.reach)) continue;
    int k0, k1;
    voxelRange(s.position.z, s.radius, g.lo.z, g.invH.z, g.n.z, k0, k1);
    for (int k = k0; k <= k1; ++k) slices[std::size_t(k)].push_back(int(j));
  }
  return slices;
}

/// One row's accumulators (structure of arrays, so the row loops vectorise).
struct RowSums {
  float* r;
  float* g;
  float* b;
  float* w;
};

/// Occlusion-aware weights exp(−σt·τ) of the segments from sample position p to the voxel
/// centres i0..i1 of the row at (y, z), into occ[i]: τ by the midpoint rule with steps of at
/// most one density voxel (a thinner step would not see more of the trilinear field; a
/// coarser one misses thin sheets).
void occlusionWeights(const Gather& g, const Vec3& p, float y, float z, int i0, int i1,
                      float* occ) {
  for (int i = i0; i <= i1; ++i) {
    const Vec3 seg = Vec3(g.lo.x + (float(i) + 0.5f) * g.h.x, y, z) - p;
    const float len = glm::length(seg);
    const int steps = stepCount(len, g.densityVoxel);
    float sum = 0.0f;
    for (int m = 0; m < steps; ++m)
      sum += g.density.sample(p + seg * ((float(m) + 0.5f) / float(steps)));
    occ[std::size_t(i)] = std::exp(-g.occlusionSigmaT * sum * (len / float(steps)));
  }
}

/// Sample s's Eq. 4 terms on voxels i0..i1 of row j of slice z (dy, dz from s; c = dy² + dz²),
/// with the occlusion weights and the bounded Taylor terms as `g` asks (cpu/gather_rows.h).
void addGradientRow(const Gather& g, const RadianceSample& s, RowSums row, int i0, int i1, int j,
                    float z, float dy, float dz, float c, float* occ) {
  const Vec3 p = s.position;
  const float R = s.radius;
  const float lox = g.lo.x, hx = g.h.x;
  if (g.occlusionSigmaT > 0.0f) {
    occlusionWeights(g, p, g.lo.y + (float(j) + 0.5f) * g.h.y, z, i0, i1, occ);
    if (g.bounds)
      gradientRowBounded(row.r, row.g, row.b, row.w, i0, i1, lox, hx, p.x, c, R, kSingularEps,
                         s.S + dy * s.dS[1] + dz * s.dS[2], s.dS[0], occ, g.bounds->lo,
                         g.bounds->hi);
    else
      gradientRowWeighted(row.r, row.g, row.b, row.w, i0, i1, lox, hx, p.x, c, R, kSingularEps,
                          s.S + dy * s.dS[1] + dz * s.dS[2], s.dS[0], occ);
  } else if (g.bounds) {
    gradientRowBounded(row.r, row.g, row.b, row.w, i0, i1, lox, hx, p.x, c, R, kSingularEps,
                       s.S + dy * s.dS[1] + dz * s.dS[2], s.dS[0], nullptr, g.bounds->lo,
                       g.bounds->hi);
  } else {
    gradientRow(row.r, row.g, row.b, row.w, i0, i1, lox, hx, p.x, c, R, kSingularEps,
                s.S + dy * s.dS[1] + dz * s.dS[2], s.dS[0]);
  }
}

/// Sample s's normalised-RBF terms w·B(x) on voxels i0..i1 of a row (c = dy² + dz²).
void addRbfRow(const Gather& g, const RadianceSample& s, RowSums row, int i0, int i1, float c) {
  const Vec3 p = s.position;
  const float R2 = s.radius * s.radius;
  const float invR2 = 9.0f / R2;  // 1 / r², r = R/3
  float* __restrict r0 = row.r;
  float* __restrict g0 = row.g;
  float* __restrict b0 = row.b;
  float* __restrict w0 = row.w;
  for (int i = i0; i <= i1; ++i) {
    const float dx = (g.lo.x + (float(i) + 0.5f) * g.h.x) - p.x;
    const float d2 = dx * dx + c;
    const float wAll = s.weight * std::exp(-d2 * invR2);
    const float w = d2 < R2 ? wAll : 0.0f;
    r0[i] += w * s.S.x;
    g0[i] += w * s.S.y;
    b0[i] += w * s.S.z;
    w0[i] += w;
  }
}

/// Sample s as the nearest so far of voxels i0..i1 of a row where it is nearer than the one
/// kept (w holds the squared distance of the one kept).
void keepNearestRow(const Gather& g, const RadianceSample& s, RowSums row, int i0, int i1,
                    float c) {
  const Vec3 p = s.position;
  const float R2 = s.radius * s.radius;
  float* __restrict r0 = row.r;
  float* __restrict g0 = row.g;
  float* __restrict b0 = row.b;
  float* __restrict w0 = row.w;
  for (int i = i0; i <= i1; ++i) {
    const float dx = (g.lo.x + (float(i) + 0.5f) * g.h.x) - p.x;
    const float d2 = dx * dx + c;
    if (d2 < R2 && d2 < w0[i]) {
      w0[i] = d2;
      r0[i] = s.S.x;
      g0[i] = s.S.y;
      b0[i] = s.S.z;
    }
  }
}

/// Adds every sample of `slice` (the ones whose spheres reach slice k) to the slice's
/// accumulators, and widens each row's touched span.
void accumulateSlice(const Gather& g, int k, const std::vector<int>& slice,
                     SliceAccumulators& acc) {
  const IVec3 n = g.n;
  const float z = g.lo.z + (float(k) + 0.5f) * g.h.z;
  int* spanLo = acc.spanLo.data();
  int* spanHi = acc.spanHi.data();
  const bool padRows = g.kind == Interpolation::Gradient && !(g.occlusionSigmaT > 0.0f);
  for (int idx : slice) {
    const RadianceSample& s = g.samples[std::size_t(idx)];
    const Vec3 p = s.position;
    const float R2 = s.radius * s.radius;
    const float dz = z - p.z;
    const float remZ = R2 - dz * dz;
    if (!(remZ > 0.0f)) continue;
    int j0, j1;
    voxelRange(p.y, std::sqrt(remZ), g.lo.y, g.invH.y, n.y, j0, j1);
    for (int j = j0; j <= j1; ++j) {
      const float dy = (g.lo.y + (float(j) + 0.5f) * g.h.y) - p.y;
      const float c = dy * dy + dz * dz;
      const float rem = R2 - c;
      if (!(rem > 0.0f)) continue;
      int i0, i1;
      voxelRange(p.x, std::sqrt(rem), g.lo.x, g.invH.x, n.x, i0, i1);
      if (i0 > i1) continue;  // the sphere's row lies outside the volume
      if (padRows) {
        // Whole batches of 8 voxels where the row allows: the extra voxels lie outside the
        // sphere (weight 0, nothing added), and the row loop then has no scalar remainder,
        // which costs a square root and a division per voxel.
        const int padded = (i1 - i0 + 8) & ~7;
        i0 = std::max(0, i1 - padded + 1);
        i1 = std::min(n.x - 1, i0 + padded - 1);
      }
      spanLo[j] = std::min(spanLo[j], i0);
      spanHi[j] = std::max(spanHi[j], i1);
      const std::size_t o = std::size_t(j) * n.x;
      const RowSums row{acc.r.data() + o, acc.g.data() + o, acc.b.data() + o, acc.w.data() + o};
      switch (g.kind) {
        case Interpolation::Gradient:
          addGradientRow(g, s, row, i0, i1, j, z, dy, dz, c, acc.occ.data());
          break;
        case Interpolation::Rbf:
          addRbfRow(g, s, row, i0, i1, c);
          break;
        case Interpolation::Nearest:
          keepNearestRow(g, s, row, i0, i1, c);
          break;
      }
    }
  }
}

/// The value of an occupied voxel (i, j, k) no sample covers: the nearest sample's.
Vec3 uncoveredValue(const Gather& g, int i, int j, int k) {
  const int m = g.nearest.nearest(g.out.cellCenter(i, j, k));
  const Vec3 v = m >= 0 ? g.samples[std::size_t(m)].S : Vec3(0.0f);
  return g.log ? glm::exp(v) : clampNonNegative(v);
}

/// Writes row j of slice k of the output (and of the weight sums) from the accumulators:
/// normalisation over the touched span [spanLo, spanHi]; outside it no sphere reached, so a
/// voxel there is zero unless it is occupied (then it takes the nearest sample), and occupancy
/// is only looked at where no sphere reached (UncoveredOccupancy: no density read outside the
/// density rows' non-zero spans). Clears what the row touched for the thread's next slice.
/// Returns the uncovered voxels.
long long writeRow(const Gather& g, int j, int k, SliceAccumulators& acc) {
  const IVec3 n = g.n;
  long long unc = 0;
  const bool fastNormalise = !g.log && g.kind != Interpolation::Nearest;
  Vec3* orow = &g.out.at(0, j, k);
  float* wrow = g.weightSum ? &g.weightSum->at(0, j, k) : nullptr;
  int a, b;  // no voxel of the row outside [a, b] is occupied
  g.occupied.rowRange(j, k, a, b);
  const int s0 = acc.spanLo[j], s1 = acc.spanHi[j];
  const char* lit = nullptr;  // LitReach of each voxel of the row (null: all lit)
  if (g.lit) {
    acc.lit.resize(std::size_t(n.x));
    bool any = false;
    for (int i = 0; i < n.x; ++i)
      any |= acc.lit[std::size_t(i)] = g.lit->reaches(g.out.cellCenter(i, j, k), g.reach);
    if (!any) a = n.x, b = -1;  // nothing to fill
    lit = acc.lit.data();
  }
  const auto uncovered = [&](int i) {
    ++unc;
    return uncoveredValue(g, i, j, k);
  };
  // An occupied voxel no sphere reached, where the march can see it.
  const auto fills = [&](int i) {
    return i >= a && i <= b && (!lit || lit[i]) && g.occupied(i, j, k);
  };
  // Voxels before and after the touched span: uncovered.
  const auto uncoveredRun = [&](int from, int to) {  // [from, to)
    std::fill(orow + from, orow + to, Vec3(0.0f));
    if (wrow) std::fill(wrow + from, wrow + to, 0.0f);
    for (int i = std::max(from, a); i < std::min(to, b + 1); ++i)
      if (fills(i)) orow[i] = uncovered(i);
  };
  if (s0 > s1) {
    uncoveredRun(0, n.x);
    return unc;
  }
  uncoveredRun(0, s0);
  const std::size_t row = std::size_t(j) * n.x;
  float* ar = acc.r.data();
  float* ag = acc.g.data();
  float* ab = acc.b.data();
  float* den = acc.w.data();
  if (fastNormalise) {
    // Gradient and Rbf, linear values: the division and clamp over the span in a loop that
    // vectorises (the same operations as the general loop below), then the stores.
    float* __restrict qr = acc.qr.data();
    float* __restrict qg = acc.qg.data();
    float* __restrict qb = acc.qb.data();
    const float* __restrict rr = ar + row;
    const float* __restrict rg = ag + row;
    const float* __restrict rb = ab + row;
    const float* __restrict rw = den + row;
    normaliseSpan(rr, rg, rb, rw, s0, s1, qr, qg, qb);
    for (int i = s0; i <= s1; ++i) {
      const float d = rw[i];
      if (d > 0.0f) {
        orow[i] = Vec3(qr[i], qg[i], qb[i]);
      } else {
        orow[i] = fills(i) ? uncovered(i) : Vec3(0.0f);
      }
      if (wrow) wrow[i] = d > 0.0f ? d : 0.0f;
    }
  }
  for (int i = s0; i <= s1 && !fastNormalise; ++i) {
    const float d = den[row + i];
    const bool covered = g.kind == Interpolation::Nearest ? d < kInfinity : d > 0.0f;
    Vec3 v;
    if (covered) {
      v = Vec3(ar[row + i], ag[row + i], ab[row + i]);
      if (g.kind != Interpolation::Nearest) v /= d;
      v = g.log ? glm::exp(v) : clampNonNegative(v);
    } else {
      v = fills(i) ? uncovered(i) : Vec3(0.0f);
    }
    orow[i] = v;
    if (wrow) wrow[i] = covered ? (g.kind == Interpolation::Nearest ? 1.0f : d) : 0.0f;
  }
  uncoveredRun(s1 + 1, n.x);
  if (lit)  // what the march multiplies by A = 0 everywhere around it
    for (int i = s0; i <= s1; ++i)
      if (!lit[i]) {
        orow[i] = Vec3(0.0f);
        if (wrow) wrow[i] = 0.0f;
      }
  // Clear what this slice touched for the next slice of this thread.
  std::fill(ar + row + s0, ar + row + s1 + 1, 0.0f);
  std::fill(ag + row + s0, ag + row + s1 + 1, 0.0f);
  std::fill(ab + row + s0, ab + row + s1 + 1, 0.0f);
  std::fill(den + row + s0, den + row + s1 + 1, g.emptyDen);
  acc.spanLo[j] = std::numeric_limits<int>::max();
  acc.spanHi[j] = -1;
  return unc;
}

}  // namespace

ReconstructionStats interpolateSamples(Interpolation kind, const DensityGrid& density,
                                       std::span<const RadianceSample> samples, RadianceGrid& out,
                                       Grid3<float>* weightSum, ValueSpace space,
                                       float occlusionSigmaT, std::optional<TaylorBounds> bounds,
                                       const LitReach* lit) {
  const IVec3 n = out.dims();
  if (lit && lit->everywhere()) lit = nullptr;
  if (weightSum) weightSum->reset(out.bounds(), n, 0.0f);
  const Vec3 dc = density.cellSize();
  const NearestIndex nearest(samples);
  const UncoveredOccupancy occupied(density, out);
  const Gather g{kind,
                 density,
                 samples,
                 out,
                 weightSum,
                 space == ValueSpace::Log,
                 occlusionSigmaT,
                 bounds,
                 n,
                 out.cellSize(),
                 out.bounds().min,
                 1.0f / out.cellSize(),
                 kind == Interpolation::Nearest ? kInfinity : 0.0f,
                 std::min(dc.x, std::min(dc.y, dc.z)),
                 nearest,
                 occupied,
                 lit,
                 glm::length(out.cellSize())};
  const std::vector<std::vector<int>> slices = binBySlice(g);
  const std::size_t nxy = std::size_t(n.x) * n.y;
  // Accumulators of one slice, per thread, allocated and cleared once: after a slice only the
  // span each row was touched in is cleared again (writeRow).
  tbb::enumerable_thread_specific<SliceAccumulators> scratch(
      [&] { return SliceAccumulators(nxy, std::size_t(n.y), std::size_t(n.x), g.emptyDen); });
  std::atomic<long long> uncovered{0};
  tbb::parallel_for(0, n.z, [&](int k) {
    SliceAccumulators& acc = scratch.local();
    accumulateSlice(g, k, slices[std::size_t(k)], acc);
    long long unc = 0;
    for (int j = 0; j < n.y; ++j) unc += writeRow(g, j, k, acc);
    uncovered += unc;
  });
  ReconstructionStats st;
  st.uncovered = uncovered.load();
  return st;
}

PointEstimate interpolateAt(Interpolation kind, const Vec3& x,
                            std::span<const RadianceSample> samples) {
  PointEstimate e;
  Vec3 num(0.0f);
  float bestD2 = kInfinity;
  for (const RadianceSample& s : samples) {
    if (!usable(s)) continue;
    const float dx = x.x - s.position.x, dy = x.y - s.position.y, dz = x.z - s.position.z;
    const float d2 = dx * dx + (dy * dy + dz * dz);
    const float R = s.radius;
    if (!(d2 < R * R)) continue;
    ++e.covering;
    switch (kind) {
      case Interpolation::Gradient: {
        const float w = R / std::max(std::sqrt(d2), kSingularEps * R);
        num += w * s.taylor(x);
        e.weightSum += w;
        break;
      }
      case Interpolation::Rbf: {
        const float w = s.weight * std::exp(-d2 * 9.0f / (R * R));
        num += w * s.S;
        e.weightSum += w;
        break;
      }
      case Interpolation::Nearest:
        if (d2 < bestD2) {
          bestD2 = d2;
          num = s.S;
          e.weightSum = 1.0f;
        }
        break;
    }
  }
  if (e.weightSum > 0.0f) e.value = kind == Interpolation::Nearest ? num : num / e.weightSum;
  return e;
}

namespace {

/// The frame's radiance volume, new over the medium box with `dims` voxels.
RadianceGrid& newRadiance(Frame& frame, const Scene& scene, IVec3 dims) {
  HostFrame& f = static_cast<HostFrame&>(frame);
  f.radiance = std::make_shared<RadianceGrid>(scene.medium.bounds, dims);
  return *f.radiance;
}

class InterpolatingReconstruction : public Reconstruction {
 public:
  /// lamp: the values are V with LampModel (PipelineSettings::lampModel); the bounds' hi is
  /// tightened per frame (lampBounds).
  /// factored: the volume holds V = S / A, so voxels no spot cone reaches are left 0 (LitReach).
  InterpolatingReconstruction(Interpolation k, ValueSpace space, bool occlusion,
                              std::optional<TaylorBounds> bounds, bool lamp, bool factored)
      : kind_(k),
        space_(space),
        occlusion_(occlusion),
        bounds_(bounds),
        lamp_(lamp),
        factored_(factored) {}
  bool needsGradients() const override { return kind_ == Interpolation::Gradient; }
  ReconstructionStats reconstruct(Frame& frame, const Scene& scene,
                                  std::span<const RadianceSample> samples, IVec3 dims,
                                  Progress*) override {
    const DensityGrid& density = frame.hostDensity();
    std::optional<TaylorBounds> bounds = bounds_;
    if (bounds && lamp_) bounds = lampBounds(*bounds, scene, density);
    const LitReach lit(scene.lights);
    return interpolateSamples(kind_, density, samples, newRadiance(frame, scene, dims), nullptr,
                              space_, occlusion_ ? scene.medium.sigmaT : 0.0f, bounds,
                              factored_ ? &lit : nullptr);
  }

 private:
  Interpolation kind_;
  ValueSpace space_;
  bool occlusion_;
  std::optional<TaylorBounds> bounds_;
  bool lamp_, factored_;
};

class PerVoxelReconstruction : public Reconstruction {
 public:
  /// `factored`, `lampModel`: the volume holds what the pipeline's march expects (V = S / A with
  /// factor_lights: adaptive's whole-scene fallback; per-voxel itself holds S).
  PerVoxelReconstruction(float delta1, bool factored, bool lampModel, bool simdShadows)
      : delta1_(delta1), factored_(factored), lampModel_(lampModel), simdShadows_(simdShadows) {}
  bool needsGradients() const override { return false; }
  bool usesSamples() const override { return false; }
  ReconstructionStats reconstruct(Frame& frame, const Scene& scene, std::span<const RadianceSample>,
                                  IVec3 dims, Progress* progress) override {
    if (progress) progress->restart("per-voxel S", dims.z);
    const PerVoxelStats pv =
        buildPerVoxelRadiance(scene, frame.hostDensity(), delta1_, newRadiance(frame, scene, dims),
                              progress, factored_, lampModel_, simdShadows_);
    ReconstructionStats st;
    st.traced = pv.traced;
    st.skipped = pv.skipped;
    return st;
  }

 private:
  float delta1_;
  bool factored_, lampModel_, simdShadows_;
};

/// The keys of the reconstructions from samples (gradient, rbf, nearest; the extensions of
/// docs/fidelity.md, which only gradient's Taylor terms use).
const std::vector<KeyDoc>& interpolationKeys() {
  static const std::vector<KeyDoc> keys = {
      {"occlusion_weights", "bool", "false", "true, false (true not with paper)",
       "Eq. 4 weights times exp(−σt·τ) of the segment sample → voxel: no sample contributes "
       "across a dense occluder; gradient reconstruction",
       "true"},
      {"bounded_taylor", "bool", "true (false with paper)", "true, false (true not with paper)",
       "clamp each sample's Taylor estimate to the known range of what is interpolated (V in "
       "[0, 1], ln V <= 0, S >= 0) before weighting; gradient reconstruction",
       "false"},
      {"log_space", "bool",
       "false for methods that refine their samples (adaptive; docs/fidelity.md, \"log_space "
       "re-checked on the population\"); for the others true with factor_lights and "
       "bounded_taylor in scenes without objects whose densest voxel has an optical depth "
       "σt·D_max·h ≥ 0.5 (h the largest voxel edge; D_max from the density model: uniform, "
       "height, grid, VDB, sums of up to 4096 Gaussians; docs/fidelity.md §14), else false",
       "true, false (true needs factor_lights)",
       "interpolate ln V (a light-weighted optical depth, nearly linear) and store exp of it; "
       "dynamic sampling then measures its error on V; methods with samples",
       "true"},
  };
  return keys;
}

/// log_space's default threshold: the optical depth across the densest voxel (1 − e^−0.5: it
/// stops 40 % of the light). The fidelity scenes lie at <= 0.25 or >= 1.0 (docs/fidelity.md §14).
constexpr float kOpaqueVoxelDepth = 0.5f;

void parseInterpolation(Params& p, const Scene& scene, PipelineSettings& s) {
  // Off by default: measured (docs/fidelity.md) a clear win with adaptive on occluders (the
  // perforated sheet, the chimney trail) but 3-30x the frame time and worse on smoke1.
  s.occlusionWeights = p.boolean("occlusion_weights", false);
  if (s.paper && s.occlusionWeights)
    p.fail("occlusion_weights", "is an extension; it cannot be true with render.paper = true");
  s.boundedTaylor = p.boolean("bounded_taylor", !s.paper);
  if (s.paper && s.boundedTaylor)
    p.fail("bounded_taylor", "is an extension; it cannot be true with render.paper = true");
  // Default chosen by measurement (docs/fidelity.md §14): with fixed samples ln V wins where
  // single voxels are nearly opaque (a voxel's optical depth σt·D·h >= 0.5: smoke1, chimney,
  // the thin sheets), whose shadows a linear V between samples cannot follow, and loses in
  // optically thin media (lamps in fog, glow, thick clouds: every voxel <= 0.25) and, badly, at
  // the hard shadows of scene objects (window: 3.4 % -> 10.9 %), where ln V falls to ln kMinV.
  // Not where the Taylor terms are unbounded: exp of an unbounded extrapolation of ln V
  // overflows (§14). Where samples are refined by their error (adaptive), V wins on every
  // population scene where the two differ (the sheets 3.8 -> 2.2 %, the clouds ~2x): never
  // ln V by default there (docs/fidelity.md, "log_space re-checked on the population").
  const std::optional<float> peak =
      scene.medium.density ? scene.medium.density->peak() : std::optional<float>();
  const Vec3 voxel = scene.medium.bounds.extent() / Vec3(scene.medium.resolution);
  const bool opaqueVoxels =
      peak &&
      scene.medium.sigmaT * *peak * std::max({voxel.x, voxel.y, voxel.z}) >= kOpaqueVoxelDepth;
  s.logSpace = p.boolean("log_space", s.factorLights && !s.paper && !s.refinedSamples &&
                                          !scene.objects && opaqueVoxels && s.boundedTaylor);
  if (s.logSpace && !s.factorLights)
    p.fail("log_space", "interpolates ln V of factor_lights; it needs factor_lights = true");
}

}  // namespace

void registerReconstructions() {
  const auto interp = [](Interpolation k) {
    return [k](const PipelineSettings& s) {
      const ValueSpace space = s.logValues() ? ValueSpace::Log : ValueSpace::Linear;
      return std::unique_ptr<Reconstruction>(
          new InterpolatingReconstruction(k, space, s.occlusionWeights, taylorBounds(s),
                                          s.tracerSteps().lampModel, s.tracerSteps().reach > 0.0f));
    };
  };
  const StageDecl fromSamples{.keys = {{interpolationKeys, parseInterpolation}}};
  for (const auto& [name, kind] : {std::pair{"gradient", Interpolation::Gradient},
                                   {"rbf", Interpolation::Rbf},
                                   {"nearest", Interpolation::Nearest}}) {
    reconstructions().declare(name, fromSamples);
    reconstructions().addVariant(name, Backend::Cpu, interp(kind));
  }
  reconstructions().declare("per-voxel", {.lightWork = LightWork::EveryVoxel});
  reconstructions().addVariant("per-voxel", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Reconstruction>(new PerVoxelReconstruction(
        s.delta1, s.factorLights, s.tracerSteps().lampModel, s.tracerSteps().simdShadows));
  });
}

}  // namespace scatterlab
