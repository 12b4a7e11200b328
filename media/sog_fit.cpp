#include "media/sog_fit.h"

#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <unsupported/Eigen/NonLinearOptimization>

#include "core/error.h"
#include "media/dense_grid.h"

namespace scatterlab {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

constexpr float kCull = GaussianDensity::kCullRadius;

/// Inclusive cell range of `g` whose centres may lie within `R` of `c` (clamped; empty when
/// lo > hi in some axis).
void cellRange(const DensityGrid& g, const Vec3& c, float R, IVec3& lo, IVec3& hi) {
  const Vec3 cell = g.cellSize(), mn = g.bounds().min, nf(g.dims());
  lo = IVec3(glm::clamp(glm::floor((c - R - mn) / cell - 0.5f), Vec3(0), nf));
  hi = IVec3(glm::clamp(glm::ceil((c + R - mn) / cell - 0.5f), Vec3(-1), nf - 1.0f));
}

/// Calls f(i, j, k, g) for every cell of `grid` within the culling radius of `b`, with g the
/// unit-weight Gaussian there.
template <class F>
void forSupport(const DensityGrid& grid, const GaussianBlob& b, float R, const F& f) {
  IVec3 lo, hi;
  cellRange(grid, b.center, R, lo, hi);
  const float r2 = b.radius * b.radius;
  for (int k = lo.z; k <= hi.z; ++k)
    for (int j = lo.y; j <= hi.y; ++j)
      for (int i = lo.x; i <= hi.x; ++i) {
        const Vec3 v = grid.cellCenter(i, j, k) - b.center;
        const float q = glm::dot(v, v);
        if (q < R * R) f(i, j, k, std::exp(-q / r2));
      }
}

/// Least-squares problem of one Gaussian against a target over sample cells:
/// e_v = w exp(−|x_v − c|²/r²) − T_v, parameters (cx, cy, cz, log r, w).
struct LocalFit {
  using Scalar = double;
  enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };
  using InputType = Eigen::VectorXd;
  using ValueType = Eigen::VectorXd;
  using JacobianType = Eigen::MatrixXd;

  std::vector<Eigen::Vector3d> x;
  std::vector<double> t;
  int inputs() const { return 5; }
  int values() const { return int(x.size()); }

  int operator()(const Eigen::VectorXd& p, Eigen::VectorXd& e) const {
    const Eigen::Vector3d c = p.head<3>();
    const double r2 = std::exp(2.0 * p[3]), w = p[4];
    for (size_t v = 0; v < x.size(); ++v)
      e[Eigen::Index(v)] = w * std::exp(-(x[v] - c).squaredNorm() / r2) - t[v];
    return 0;
  }
  int df(const Eigen::VectorXd& p, Eigen::MatrixXd& J) const {
    const Eigen::Vector3d c = p.head<3>();
    const double r2 = std::exp(2.0 * p[3]), w = p[4];
    for (size_t v = 0; v < x.size(); ++v) {
      const Eigen::Vector3d d = x[v] - c;
      const double q = d.squaredNorm(), g = std::exp(-q / r2);
      const Eigen::Index row = Eigen::Index(v);
      J.block<1, 3>(row, 0) = (w * g * 2.0 / r2) * d.transpose();  // ∂/∂c
      J(row, 3) = w * g * 2.0 * q / r2;                            // ∂/∂ log r
      J(row, 4) = g;                                               // ∂/∂w
    }
    return 0;
  }
};

}  // namespace

double relativeL2(const std::vector<float>& a, const std::vector<float>& b) {
  double num = 0, den = 0;
  for (size_t i = 0; i < b.size(); ++i) {
    const double d = double(a[i]) - double(b[i]);
    num += d * d;
    den += double(b[i]) * b[i];
  }
  return den > 0 ? std::sqrt(num / den) : std::sqrt(num);
}

DensityGrid downsample(const DensityGrid& g, int f) {
  if (f <= 1) return g;
  const IVec3 n = g.dims();
  const IVec3 m = (n + f - 1) / f;
  // Coarse cells are aligned with blocks of f³ fine cells; the box grows to whole blocks.
  const Box box{g.bounds().min, g.bounds().min + Vec3(m * f) * g.cellSize()};
  DensityGrid out(box, m);
  tbb::parallel_for(0, m.z, [&](int K) {
    for (int J = 0; J < m.y; ++J)
      for (int I = 0; I < m.x; ++I) {
        double s = 0;
        int c = 0;
        for (int k = K * f; k < std::min(n.z, K * f + f); ++k)
          for (int j = J * f; j < std::min(n.y, J * f + f); ++j)
            for (int i = I * f; i < std::min(n.x, I * f + f); ++i) {
              s += g.at(i, j, k);
              ++c;
            }
        out.at(I, J, K) = float(s / c);
      }
  });
  return out;
}

namespace {

/// Step 2: greedy placement on the working grid; `res` holds the residual and is updated.
std::vector<GaussianBlob> placeGreedy(DensityGrid& res, int count, float maxD) {
  const Vec3 cs = res.cellSize();
  const float h = std::min({cs.x, cs.y, cs.z});
  // Not below 0.75 working cells: the working grid is a box filter of the input and cannot
  // resolve narrower Gaussians (they would become tall spikes at full resolution).
  const float radii[] = {0.75f, 1.05f, 1.5f, 2.1f, 3.0f, 4.2f, 6.0f, 8.4f, 12.0f};
  constexpr int nr = int(std::size(radii));
  std::vector<GaussianBlob> out;
  auto& data = res.data();
  for (int n = 0; n < count; ++n) {
    // Cell of the largest residual.
    using Best = std::pair<float, size_t>;
    const Best best = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, data.size(), 1 << 14), Best{-1.0f, 0},
        [&](const tbb::blocked_range<size_t>& r, Best b) {
          for (size_t i = r.begin(); i < r.end(); ++i)
            if (data[i] > b.first) b = {data[i], i};
          return b;
        },
        [](const Best& a, const Best& b) {
          return a.first > b.first || (a.first == b.first && a.second < b.second) ? a : b;
        });
    if (best.first <= 1e-6f * maxD) break;  // nothing left to explain
    const IVec3 d = res.dims();
    const int i = int(best.second % size_t(d.x)), j = int(best.second / size_t(d.x) % size_t(d.y)),
              k = int(best.second / (size_t(d.x) * size_t(d.y)));
    const Vec3 c = res.cellCenter(i, j, k);
    // Weight = the peak residual (so the peak is explained and the next maximum lies
    // elsewhere); radius among the candidates with the largest drop of the squared residual,
    // 2 w Σ R g − w² Σ g² (the smallest candidate when none lowers it).
    const double w = best.first;
    double drop[nr];
    tbb::parallel_for(0, nr, [&](int ri) {
      GaussianBlob b{c, radii[ri] * h, 1.0f};
      double a = 0, bb = 0;
      forSupport(res, b, kCull * b.radius, [&](int x, int y, int z, float g) {
        a += double(res.at(x, y, z)) * g;
        bb += double(g) * g;
      });
      drop[ri] = 2 * w * a - w * w * bb;
    });
    int pick = 0;
    for (int ri = 1; ri < nr; ++ri)
      if (drop[ri] > drop[pick]) pick = ri;
    const GaussianBlob b{c, radii[pick] * h, float(w)};
    forSupport(res, b, kCull * b.radius,
               [&](int x, int y, int z, float g) { res.at(x, y, z) -= b.weight * g; });
    out.push_back(b);
  }
  return out;
}

/// Step 3: one refinement sweep (block-coordinate Levenberg–Marquardt) on the working grid.
void refineSweep(DensityGrid& res, std::vector<GaussianBlob>& gs, const SogFitOptions& o) {
  const Vec3 cs = res.cellSize();
  const float h = std::min({cs.x, cs.y, cs.z});
  const float maxR =
      0.5f * std::max({res.bounds().extent().x, res.bounds().extent().y, res.bounds().extent().z}) /
      kCull;
  for (GaussianBlob& b : gs) {
    const float boxR = 1.5f * kCull * b.radius;  // region the refined Gaussian may occupy
    IVec3 lo, hi;
    cellRange(res, b.center, boxR, lo, hi);
    if (glm::any(glm::greaterThan(lo, hi))) continue;
    // Target T = residual + this Gaussian, over the region.
    forSupport(res, b, kCull * b.radius,
               [&](int x, int y, int z, float g) { res.at(x, y, z) += b.weight * g; });
    const IVec3 ext = hi - lo + 1;
    const double cells = double(ext.x) * ext.y * ext.z;
    const int stride = std::max(1, int(std::ceil(std::cbrt(cells / o.lmMaxSamples))));
    LocalFit fit;
    for (int k = lo.z; k <= hi.z; k += stride)
      for (int j = lo.y; j <= hi.y; j += stride)
        for (int i = lo.x; i <= hi.x; i += stride) {
          const Vec3 p = res.cellCenter(i, j, k);
          fit.x.emplace_back(p.x, p.y, p.z);
          fit.t.push_back(res.at(i, j, k));
        }
    if (fit.x.size() >= 6) {
      Eigen::VectorXd p(5);
      p << b.center.x, b.center.y, b.center.z, std::log(double(b.radius)), b.weight;
      Eigen::VectorXd e0(fit.values()), e1(fit.values());
      fit(p, e0);
      const Eigen::VectorXd p0 = p;
      Eigen::LevenbergMarquardt<LocalFit> lm(fit);
      lm.parameters.maxfev = o.lmMaxEvaluations;
      lm.parameters.xtol = 1e-6;
      lm.parameters.ftol = 1e-8;
      lm.minimize(p);
      // Keep the Gaussian inside its region and its radius sane; accept only improvements.
      const double r = std::exp(p[3]);
      const Eigen::Vector3d c0 = p0.head<3>();
      const bool ok = p.allFinite() && p[4] > 0 && r >= 0.75 * h && r <= maxR &&
                      kCull * r <= boxR && (p.head<3>() - c0).norm() <= 0.5 * boxR;
      if (ok) {
        fit(p, e1);
        if (e1.squaredNorm() < e0.squaredNorm()) {
          b.center = Vec3(float(p[0]), float(p[1]), float(p[2]));
          b.radius = float(r);
          b.weight = float(p[4]);
        }
      }
    }
    forSupport(res, b, kCull * b.radius,
               [&](int x, int y, int z, float g) { res.at(x, y, z) -= b.weight * g; });
  }
}

/// Step 4: exact linear least squares for the weights on the full-resolution input,
/// non-negative by eliminating negative weights and re-solving. Returns the Gaussians kept.
std::vector<GaussianBlob> solveWeights(const DensityGrid& D, std::vector<GaussianBlob> gs) {
  const int N = int(gs.size());
  if (N == 0) return gs;
  const IVec3 n = D.dims();
  // Gaussians sorted by their lowest z cell let each slab find its candidates quickly.
  std::vector<IVec3> glo(static_cast<size_t>(N)), ghi(static_cast<size_t>(N));
  for (int a = 0; a < N; ++a)
    cellRange(D, gs[size_t(a)].center, kCull * gs[size_t(a)].radius, glo[size_t(a)],
              ghi[size_t(a)]);
  struct Acc {
    Eigen::MatrixXd G;
    Eigen::VectorXd b;
  };
  tbb::combinable<Acc> acc([N] {
    return Acc{Eigen::MatrixXd::Zero(N, N), Eigen::VectorXd::Zero(N)};
  });
  tbb::parallel_for(tbb::blocked_range<int>(0, n.z, 2), [&](const tbb::blocked_range<int>& r) {
    Acc& A = acc.local();
    std::vector<int> zc, yc, ids;
    std::vector<double> vals;
    for (int a = 0; a < N; ++a)
      if (glo[size_t(a)].z < r.end() && ghi[size_t(a)].z >= r.begin()) zc.push_back(a);
    for (int k = r.begin(); k < r.end(); ++k)
      for (int j = 0; j < n.y; ++j) {
        yc.clear();
        for (int a : zc)
          if (glo[size_t(a)].z <= k && ghi[size_t(a)].z >= k && glo[size_t(a)].y <= j &&
              ghi[size_t(a)].y >= j)
            yc.push_back(a);
        if (yc.empty()) continue;
        for (int i = 0; i < n.x; ++i) {
          ids.clear();
          vals.clear();
          const Vec3 p = D.cellCenter(i, j, k);
          for (int a : yc) {
            if (glo[size_t(a)].x > i || ghi[size_t(a)].x < i) continue;
            const GaussianBlob& g = gs[size_t(a)];
            const Vec3 v = p - g.center;
            const float q = glm::dot(v, v), R = kCull * g.radius;
            if (q < R * R) {
              ids.push_back(a);
              vals.push_back(std::exp(-q / (g.radius * g.radius)));
            }
          }
          const double dv = D.at(i, j, k);
          for (size_t s = 0; s < ids.size(); ++s) {
            A.b[ids[s]] += vals[s] * dv;
            for (size_t t = s; t < ids.size(); ++t) A.G(ids[s], ids[t]) += vals[s] * vals[t];
          }
        }
      }
  });
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(N, N);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(N);
  acc.combine_each([&](const Acc& a) {
    G += a.G;
    b += a.b;
  });
  // Symmetrise: only pairs (s <= t) in list order were accumulated.
  Eigen::MatrixXd Gs = G + G.transpose();
  Gs.diagonal() = G.diagonal();
  // Non-negative least squares min ½wᵀGw − bᵀw, w >= 0, by projected Gauss–Seidel
  // (coordinate descent) started from the refined weights: robust where many overlapping
  // Gaussians make G ill-conditioned (a plain solve then flips signs wildly).
  Eigen::VectorXd w(N);
  for (int a = 0; a < N; ++a) w[a] = std::max(0.0f, gs[size_t(a)].weight);
  Eigen::VectorXd Gw = Gs * w;
  for (int sweep = 0; sweep < 500; ++sweep) {
    double change = 0, scale = 0;
    for (int a = 0; a < N; ++a) {
      const double gaa = Gs(a, a);
      if (!(gaa > 0)) {
        w[a] = 0;
        continue;
      }
      const double nw = std::max(0.0, w[a] + (b[a] - Gw[a]) / gaa);
      const double d = nw - w[a];
      if (d != 0) {
        Gw += d * Gs.col(a);
        w[a] = nw;
      }
      change = std::max(change, std::abs(d));
      scale = std::max(scale, nw);
    }
    if (change <= 1e-7 * scale) break;
  }
  std::vector<GaussianBlob> out;
  for (int a = 0; a < N; ++a)
    if (w[a] > 0) {
      GaussianBlob g = gs[size_t(a)];
      g.weight = float(w[a]);
      out.push_back(g);
    }
  return out;
}

/// Step 5, mass-preserving: the residual of each cell plus the error carried into it is
/// quantised (kept only when it exceeds the threshold and does not round to 0); what the model
/// then misses at that cell, D + carry − max(0, D̃ + code·step), is passed on to the next cells
/// in x, y and z (⅓ each, renormalised at the lattice faces). This is 3-D error diffusion:
/// thin smoke below the threshold comes back as sparse entries whose sum matches what was
/// dropped locally, instead of vanishing (a systematic loss that darkens/thins the render), and
/// the clamp at 0 is accounted for. Sequential (x fastest): each cell depends on its
/// predecessors.
void diffuseResidual(const DensityGrid& D, const DensityGrid& approx, float thr, float step,
                     float qmax, ResidualHash& out) {
  const IVec3 n = D.dims();
  const std::size_t sx = 1, sy = std::size_t(n.x), sz = std::size_t(n.x) * std::size_t(n.y);
  std::vector<double> carry(D.size(), 0.0);
  const double keep = std::max(double(thr), 0.5 * step);  // smaller codes round to 0
  std::size_t idx = 0;
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i, ++idx) {
        const double target = double(D.data()[idx]) + carry[idx];
        const double g = approx.data()[idx];
        const double v = target - g;
        int code = 0;
        if (std::abs(v) > keep)
          code = int(std::lround(std::clamp(v / step, -double(qmax), double(qmax))));
        // The float the model will produce at this centre (SogModel::eval's arithmetic).
        const double model = code != 0 ? std::max(0.0f, approx.data()[idx] + float(code) * step)
                                       : std::max(0.0f, approx.data()[idx]);
        if (code != 0) out.insert(std::uint32_t(idx), std::int16_t(code));
        const double e = target - model;
        const bool hx = i + 1 < n.x, hy = j + 1 < n.y, hz = k + 1 < n.z;
        const int parts = int(hx) + int(hy) + int(hz);
        if (parts == 0 || e == 0) continue;
        const double share = e / parts;
        if (hx) carry[idx + sx] += share;
        if (hy) carry[idx + sy] += share;
        if (hz) carry[idx + sz] += share;
      }
}

}  // namespace

SogModel fitSog(const DensityGrid& D, const SogFitOptions& o, SogFitReport* report) {
  const auto t0 = Clock::now();
  if (o.gaussians < 1 || o.gaussians > 1 << 20)
    throw ConfigError("fit: gaussians = " + std::to_string(o.gaussians) +
                      "; allowed: 1 .. 1048576");
  if (!(o.threshold >= 0 && o.threshold < 1))
    throw ConfigError("fit: threshold = " + std::to_string(o.threshold) +
                      "; allowed: 0 <= threshold < 1 (fraction of the maximum density)");
  if (o.bits != 8 && o.bits != 16)
    throw ConfigError("fit: bits = " + std::to_string(o.bits) + "; allowed: 8 or 16");
  if (o.fitVoxels < 8) throw ConfigError("fit: fit-voxels must be at least 8");
  const auto log = [&](const std::string& s) {
    if (o.log) o.log(s);
  };
  float maxD = 0;
  for (float v : D.data()) maxD = std::max(maxD, v);
  if (!(maxD > 0)) throw LimitError("fit: the input density is zero everywhere");

  SogFitReport rep;
  // 1. Working grid.
  const IVec3 n = D.dims();
  const double total = double(n.x) * n.y * n.z;
  const int f = std::max(1, int(std::ceil(std::cbrt(total / double(o.fitVoxels)) - 1e-9)));
  DensityGrid work = downsample(D, f);
  rep.fitDims = work.dims();
  log("working grid " + std::to_string(work.dims().x) + "x" + std::to_string(work.dims().y) + "x" +
      std::to_string(work.dims().z) + " (input downsampled by " + std::to_string(f) + ")");

  // 2. Placement (or warm start), leaving the residual in `work`.
  auto t = Clock::now();
  std::vector<GaussianBlob> gs;
  if (o.init && !o.init->empty()) {
    gs = *o.init;
    for (const GaussianBlob& b : gs)
      forSupport(work, b, kCull * b.radius,
                 [&](int x, int y, int z, float g) { work.at(x, y, z) -= b.weight * g; });
  } else {
    gs = placeGreedy(work, o.gaussians, maxD);
  }
  rep.secondsPlacement = since(t);
  log("placed " + std::to_string(gs.size()) + " Gaussians in " +
      std::to_string(rep.secondsPlacement) + " s");

  // 3. Refinement.
  t = Clock::now();
  for (int s = 0; s < o.sweeps; ++s) refineSweep(work, gs, o);
  rep.secondsRefinement = since(t);
  {
    float rmin = kInfinity, rmax = 0, wmin = kInfinity, wmax = -kInfinity;
    for (const GaussianBlob& b : gs) {
      rmin = std::min(rmin, b.radius), rmax = std::max(rmax, b.radius);
      wmin = std::min(wmin, b.weight), wmax = std::max(wmax, b.weight);
    }
    log("  radii " + std::to_string(rmin) + " .. " + std::to_string(rmax) + ", weights " +
        std::to_string(wmin) + " .. " + std::to_string(wmax));
  }
  log("refined (" + std::to_string(o.sweeps) + " sweeps) in " +
      std::to_string(rep.secondsRefinement) + " s");

  // 4. Weights on the full-resolution input.
  t = Clock::now();
  if (o.finalWeightSolve) gs = solveWeights(D, std::move(gs));
  rep.secondsWeights = since(t);
  log("weights solved on the input grid in " + std::to_string(rep.secondsWeights) +
      " s: " + std::to_string(gs.size()) + " Gaussians with positive weight");

  // 5. Residual hash on the input lattice.
  t = Clock::now();
  SogModel m;
  m.gaussians = std::move(gs);
  m.residual = ResidualHash(D.bounds(), n, o.bits, 0.0f);
  DensityGrid approx(D.bounds(), n);
  m.splat(approx, /*withResidual=*/false);
  rep.relL2Gaussians = relativeL2(approx.data(), D.data());
  const float thr = float(o.threshold) * maxD;
  float maxF = 0;
  for (size_t i = 0; i < D.size(); ++i) {
    const float F = D.data()[i] - approx.data()[i];
    if (std::abs(F) > thr) maxF = std::max(maxF, std::abs(F));
  }
  const float qmax = float((1 << (o.bits - 1)) - 1);
  const float step = maxF > 0 ? maxF / qmax : 0.0f;
  m.residual = ResidualHash(D.bounds(), n, o.bits, step);
  m.threshold = thr;
  if (step > 0 && o.residual == SogResidualMode::Drop) {
    for (size_t i = 0; i < D.size(); ++i) {
      const float F = D.data()[i] - approx.data()[i];
      if (std::abs(F) <= thr) continue;
      const int code = int(std::lround(std::clamp(F / step, -qmax, qmax)));
      if (code != 0) m.residual.insert(std::uint32_t(i), std::int16_t(code));
    }
  } else if (step > 0) {
    diffuseResidual(D, approx, thr, step, qmax, m.residual);
  }
  m.splat(approx, /*withResidual=*/true);
  rep.relL2Model = relativeL2(approx.data(), D.data());
  {
    double sm = 0, sd = 0;
    for (size_t i = 0; i < D.size(); ++i) sm += approx.data()[i], sd += D.data()[i];
    rep.relMassModel = (sm - sd) / sd;
  }
  rep.secondsResidual = since(t);
  rep.gaussians = int(m.gaussians.size());
  rep.hashEntries = m.residual.size();
  rep.secondsTotal = since(t0);
  if (report) *report = rep;
  return m;
}

Scene sogCheckScene(const DensityGrid& D, const SogCheckView& view) {
  if (view.width < 1 || view.height < 1 || !(view.meanOpticalDepth > 0) || view.maxVoxels < 1)
    throw ConfigError("fit image check: width, height, optical depth and voxels must be > 0");
  const IVec3 n = D.dims();
  const Box box = D.bounds();
  const Vec3 ext = box.extent();
  // σt from the mean column integral along the view axis (z), over non-empty columns.
  double sum = 0;
  std::int64_t cols = 0;
  const double dz = D.cellSize().z;
  for (int j = 0; j < n.y; ++j)
    for (int i = 0; i < n.x; ++i) {
      double c = 0;
      for (int k = 0; k < n.z; ++k) c += D.at(i, j, k);
      if (c > 0) sum += c * dz, ++cols;
    }
  if (cols == 0) throw LimitError("fit image check: the input density is zero everywhere");
  Scene s;
  s.medium.bounds = box;
  s.medium.density = std::make_shared<DenseGridDensity>(D, "the fitted input");
  const double cells = double(n.x) * n.y * n.z;
  const double shrink = std::max(1.0, std::cbrt(cells / double(view.maxVoxels)));
  s.medium.resolution = glm::max(IVec3(1), IVec3(glm::floor(Vec3(n) / float(shrink))));
  s.medium.sigmaT = float(view.meanOpticalDepth / (sum / double(cols)));
  s.medium.albedo = 0.9f;
  Camera& cam = s.camera;
  cam.width = view.width;
  cam.height = view.height;
  cam.fovYDeg = 40.0f;
  const float aspect = float(view.width) / float(view.height);
  const float halfH = 0.55f * std::max(ext.y, ext.x / aspect);  // the box fills ~90 %
  const Vec3 c = box.center();
  cam.lookAt = c;
  cam.position = c - Vec3(0, 0, 0.5f * ext.z + halfH / std::tan(glm::radians(20.0f)));
  cam.up = Vec3(0, 1, 0);
  Light sun;
  sun.type = Light::Type::Directional;
  sun.direction = glm::normalize(Vec3(-1, -1, 1));
  sun.intensity = Vec3(1.0f);
  s.lights = {sun};
  s.background = Vec3(0.0f);
  s.render = Json{{"method", "exact"}};
  return s;
}

}  // namespace scatterlab
