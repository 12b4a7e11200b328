#include "sampling/dynamic_sampling.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <utility>

#include "sampling/scan.h"
#include "shading/transport.h"

namespace scatterlab {

GridInfoBuffer::GridInfoBuffer(const Box& b, int resolution)
    : bounds(b), dims(resolution), interval(b.extent() / float(resolution)) {
  const std::size_t n = std::size_t(resolution) * resolution * resolution;
  inSet.assign(n, 0);
  ancestor.assign(n, -1);
}

GridInfoBuffer::GridInfoBuffer(const Box& b, const LevelGrid& grid)
    : bounds(b), dims(grid.dims), voxels(grid.voxels), cells(grid.cells) {
  // A cubic grid's interval exactly as the int constructor computes it; the voxel grid's as
  // Grid3 computes its cell size, so its vertices are the radiance volume's voxel centres.
  if (grid.dims.x == grid.dims.y && grid.dims.y == grid.dims.z && !grid.voxels)
    interval = b.extent() / float(grid.dims.x);
  else
    interval = b.extent() / Vec3(grid.dims);
  inSet.assign(vertexCount(), 0);
  ancestor.assign(vertexCount(), -1);
}

std::vector<LevelGrid> levelGrids(const DynamicSamplingSettings& s) {
  std::vector<LevelGrid> g;
  for (int l : s.levels) g.push_back({IVec3(l), false, s.splitCells});
  if (s.voxelFallback) g.push_back({s.voxelDims, true, true});
  return g;
}

int levelProbes(const DynamicSamplingSettings& s, const LevelGrid& next) {
  return next.voxels ? std::min(s.probes, s.fallbackProbes) : s.probes;
}

DynamicSamplingSettings forInitialSamples(DynamicSamplingSettings s, const Box& bounds,
                                          const std::vector<RadianceSample>& initial) {
  if (!s.autoLevels || initial.empty()) return s;
  float r0 = 0.0f;
  for (const RadianceSample& x : initial) r0 = std::max(r0, x.radius);
  const Vec3 ext = bounds.max - bounds.min;
  const float longest = std::max(ext.x, std::max(ext.y, ext.z));
  std::erase_if(s.levels, [&](int n) { return !(longest / float(n) < r0); });
  const float last = s.levels.empty() ? longest / r0 : float(s.levels.back());
  if (float(s.finestLevel) >= 1.5f * last) s.levels.push_back(s.finestLevel);
  return s;
}

Vec3 GridInfoBuffer::vertex(std::size_t linear) const {
  const int i = int(linear % dims.x), j = int((linear / dims.x) % dims.y),
            k = int(linear / (std::size_t(dims.x) * dims.y));
  return bounds.min + (Vec3(i, j, k) + 0.5f) * interval;
}

void GridInfoBuffer::markSphere(const Vec3& c, float R, std::int32_t anc) {
  forEachChild(c, R, [&](std::size_t v) {
    std::atomic_ref<std::uint8_t>(inSet[v]).store(1, std::memory_order_relaxed);
    std::atomic_ref<std::int32_t> a(ancestor[v]);
    std::int32_t cur = a.load(std::memory_order_relaxed);
    while ((cur < 0 || anc < cur) && !a.compare_exchange_weak(cur, anc)) {
    }
  });
}

namespace {

/// Probe offsets: the 6 axis directions of Eq. 5, the 8 cube diagonals, the 12 edge diagonals
/// (unit length), then the 6 axis and 8 cube-diagonal directions at length ½ (the inner shell:
/// a shaft that passes through a sphere's inside without touching its surface near a probe).
const std::array<Vec3, kMaxProbes>& probeDirections() {
  static const std::array<Vec3, kMaxProbes> dirs = [] {
    std::array<Vec3, kMaxProbes> d{};
    int n = 0;
    for (int a = 0; a < 3; ++a)
      for (float sgn : {1.0f, -1.0f}) {
        Vec3 v(0.0f);
        v[a] = sgn;
        d[n++] = v;
      }
    for (float x : {1.0f, -1.0f})
      for (float y : {1.0f, -1.0f})
        for (float z : {1.0f, -1.0f}) d[n++] = glm::normalize(Vec3(x, y, z));
    for (int a = 0; a < 3; ++a)
      for (float u : {1.0f, -1.0f})
        for (float v : {1.0f, -1.0f}) {
          Vec3 e(0.0f);
          e[(a + 1) % 3] = u;
          e[(a + 2) % 3] = v;
          d[n++] = glm::normalize(e);
        }
    for (int i = 0; i < 14; ++i) d[n++] = 0.5f * d[std::size_t(i)];
    return d;
  }();
  return dirs;
}

}  // namespace

const Vec3* probeOffsets() {
  return probeDirections().data();
}

void probePoints(const RadianceSample& s, Vec3* out, int count) {
  const auto& dirs = probeDirections();
  for (int i = 0; i < count; ++i) out[i] = s.position + s.radius * dirs[std::size_t(i)];
}

Vec3 lightFactorTowardsEye(const LightFactor& A, const Vec3& p, const Vec3& eye) {
  return A(p, towardsEye(eye, p));
}

float mostVisibleTau(const Scene& scene, const DensityGrid& density, float tau, const Vec3* points,
                     int n, float delta1) {
  const float sigmaT = scene.medium.sigmaT;
  if (!(sigmaT > 0.0f)) return std::max(tau, 1.0f);  // no extinction: every point sees 1
  constexpr float kMargin = 1.0f + 1e-4f;
  // The depth a point must stay below to see more than `tau`.
  float bound = tau > 0.0f ? -std::log(std::min(tau, 1.0f)) / sigmaT * kMargin : kInfinity;
  for (int k = 0; k < n; ++k) {
    // Stopped once past the bound (its depth is then above it): deeper than the best, it cannot
    // raise tau. A march that finishes is opticalDepth's without a bound, bit for bit.
    const float depth = opticalDepth(density, points[k], scene.camera.position, delta1, bound);
    if (depth > bound) continue;
    tau = std::max(tau, std::exp(-sigmaT * depth));
    bound = std::min(bound, depth * kMargin);
  }
  return tau;
}

float localShadingError(const RadianceSample& s, const Vec3* probeS, const float* probeD, float tau,
                        int count, const DynamicSamplingSettings::ErrorSpace& space,
                        const Vec3* probeA, float biasWeight) {
  Vec3 p[kMaxProbes];
  probePoints(s, p, count);
  float sum = 0.0f, bias = 0.0f;
  for (int g = 0; g < count; g += kProbeGroup) {
    float group = 0.0f, groupBias = 0.0f;
    for (int i = g; i < std::min(count, g + kProbeGroup); ++i) {
      Vec3 est = s.taylor(p[i]), truth = probeS[i];
      if (space.bounds) est = space.bounds->clamp(est);
      if (space.log) {
        est = glm::exp(est);
        truth = glm::exp(truth);
      }
      Vec3 signedDiff = est - truth;
      Vec3 diff = glm::abs(signedDiff);
      if (probeA) {  // the error of S = A ⊙ V
        diff *= probeA[i];
        signedDiff *= probeA[i];
      }
      group += (diff.x + diff.y + diff.z) / 3.0f * probeD[i];
      groupBias += (signedDiff.x + signedDiff.y + signedDiff.z) / 3.0f * probeD[i];
    }
    sum += group;
    bias += groupBias;
  }
  if (biasWeight > 0.0f) sum += biasWeight * std::abs(bias);
  return s.radius * s.radius * s.radius * sum / float(count) * tau;
}

float sampleContribution(const RadianceSample& s, float density, float tau,
                         const DynamicSamplingSettings::ErrorSpace& space, const Vec3* A) {
  Vec3 a = space.log ? glm::exp(s.S) : glm::abs(s.S);
  if (A) a *= *A;
  return s.radius * s.radius * s.radius * ((a.x + a.y + a.z) / 3.0f) * density * tau;
}

double relativeErrorScale(const std::vector<float>& contributions) {
  if (contributions.empty()) return 0.0;
  double sum = 0.0;
  for (float c : contributions) sum += double(c);
  return sum / double(contributions.size());
}

float quantile(std::vector<float> v, double q) {
  if (v.empty()) return 0.0f;
  const std::size_t k = std::min(v.size() - 1, std::size_t(q * double(v.size())));
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
  return v[k];
}

namespace {

/// Transmittance from x to the camera position.
float viewTransmittance(const Scene& scene, const DensityGrid& density, const Vec3& x,
                        float delta1) {
  return std::exp(-scene.medium.sigmaT * opticalDepth(density, x, scene.camera.position, delta1));
}

}  // namespace

BudgetLimits budgetLimits(const DynamicSamplingSettings& settings, long long budget) {
  BudgetLimits b;
  if (budget <= 0) return b;
  b.sampleUnit = settings.costShare > 0.0 ? 7LL + settings.probes : 1LL;
  b.units = budget * b.sampleUnit;  // sampleBudget() caps the budget at 9e15
  b.samples = b.sampleUnit > 1 ? kFinalListPerBudget * budget : budget;
  // A max_samples the user gave stays the most samples of the final set.
  if (settings.maxSamples > 0) b.samples = std::min(b.samples, settings.maxSamples);
  return b;
}

long long sampleBudget(const DynamicSamplingSettings& settings, std::size_t initialCount) {
  long long cost = 0;  // the cost cap (0: none)
  if (settings.costShare > 0.0) {
    // Per-voxel's S evaluations: the voxels it traces where the pipeline counted them, else
    // every voxel of the radiance volume.
    const IVec3 v = settings.voxelDims;
    const double voxels = settings.perVoxelTraces > 0
                              ? double(settings.perVoxelTraces)
                              : double(std::max(v.x, 0)) * std::max(v.y, 0) * std::max(v.z, 0);
    const double samples = settings.costShare * voxels / (7.0 + settings.probes);
    cost = std::max((long long)std::min(samples, 9e15), 1LL);
  }
  if (settings.maxSamples == kAutoBudget)
    return std::max(std::min(kBudgetPerInitial * (long long)initialCount, kBudgetCap), cost);
  const long long count = std::max(settings.maxSamples, 0LL);
  return count > 0 && cost > 0 ? std::min(count, cost) : std::max(count, cost);
}

LevelEvaluation SplitPassPlan::evaluation(std::size_t k) const {
  if (k < grids.size()) return LevelEvaluation::Split;
  return k > 0 && grids[k - 1].voxels ? LevelEvaluation::FinalVoxels : LevelEvaluation::Final;
}

SplitPassPlan splitPassPlan(const DynamicSamplingSettings& settings, std::size_t initialCount) {
  SplitPassPlan plan;
  plan.grids = levelGrids(settings);
  plan.budget = sampleBudget(settings, initialCount);
  plan.limits = budgetLimits(settings, plan.budget);
  return plan;
}

std::vector<double> runSplitPass(SplitPassSteps& steps, const SplitPassPlan& plan) {
  using Clock = std::chrono::steady_clock;
  const auto since = [](Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  };
  const std::size_t L = plan.levels();
  std::vector<double> ms(L + 1, 0.0);
  for (std::size_t k = 0; k <= L; ++k) {
    const auto t0 = Clock::now();
    const LevelEvaluation e = plan.evaluation(k);
    steps.evaluate(k, e);
    if (e == LevelEvaluation::Split) {
      if (k == 0) steps.threshold();
      steps.split(k);
    }
    steps.endLevel(k);
    ms[k] = since(t0);
  }
  const auto t0 = Clock::now();
  if (plan.budget > 0 && L > 0) steps.topUp();
  steps.finish();
  ms[L] += since(t0);
  return ms;
}

int errorBin(float e, double threshold) {
  const auto key = [](float x) { return int(std::bit_cast<std::uint32_t>(x) >> kErrorBinShift); };
  return std::clamp(key(e) - key(float(threshold)), 0, kErrorBins - 1);
}

namespace {

/// The worst-first cut of a budget: with run(h) = count + Σ_{g >= h} delta[g] (the count after
/// splitting every group from the worst down to h, in units and in samples), the lowest group g
/// such that run(h) fits both limits for every h >= g, i.e. one above the highest group that
/// does not fit (kErrorBins: none fits; 0: all do). `count` receives run(cut). The GPU's cut
/// pass computes the same (suffix scans and the highest failing group).
int worstFirstCut(const std::vector<long long>& deltaUnits,
                  const std::vector<long long>& deltaSamples, BudgetCount& count,
                  long long unitLimit, long long sampleLimit) {
  BudgetCount run = count;
  int cut = kErrorBins;
  for (int g = kErrorBins - 1; g >= 0; --g) {
    run.units += deltaUnits[std::size_t(g)];
    run.samples += deltaSamples[std::size_t(g)];
    if (run.units > unitLimit || run.samples > sampleLimit) break;
    cut = g;
    count = run;
  }
  return cut;
}

/// The budget's deltas of one split level's groups: in units (its vertices of G_{k+1} at their
/// weight, less its candidates at a sample's) and in samples.
void addLevelDeltas(const SplitDecision& d, bool voxels, long long sampleUnit, int below,
                    std::vector<long long>& units, std::vector<long long>& samples) {
  const long long vertexUnit = voxels ? 1 : sampleUnit;
  for (int g = 0; g < below && g < kErrorBins; ++g) {
    const long long v = d.vertexGroups[std::size_t(g)], c = d.candidates[std::size_t(g)];
    units[std::size_t(g)] += v * vertexUnit - c * sampleUnit;
    samples[std::size_t(g)] += v - c;
  }
}

}  // namespace

SplitDecision budgetedSplit(const Box& bounds, const LevelGrid& grid,
                            const std::vector<Vec3>& centres, const std::vector<float>& radii,
                            const std::vector<std::int32_t>& anc, const std::vector<float>& errors,
                            double threshold, BudgetCount countBefore, const BudgetLimits& budget,
                            std::size_t splitLevelsLeft) {
  const std::size_t n = centres.size();
  SplitDecision d;
  d.split.assign(n, 0);
  d.count = countBefore;
  d.threshold = threshold;
  d.candidates.assign(kErrorBins, 0);
  d.vertexGroups.assign(kErrorBins, 0);
  GridInfoBuffer next(bounds, grid);
  d.vertexKey.assign(next.vertexCount(), 0);
  // The histograms: candidates per group, and each vertex under its worst marking candidate.
  std::vector<int> group(n, -1);
  for (std::size_t j = 0; j < n; ++j) {
    if (!(double(errors[j]) > threshold)) continue;
    const int g = group[j] = errorBin(errors[j], threshold);
    if (!next.voxels) ++d.candidates[std::size_t(g)];  // a fallback keeps its sample
    next.forEachChild(centres[j], radii[j], [&](std::size_t v) {
      d.vertexKey[v] = std::max(d.vertexKey[v], std::uint32_t(g + 1));
    });
  }
  for (const std::uint32_t k : d.vertexKey)
    if (k > 0) ++d.vertexGroups[k - 1];
  // This level's allotment: an equal share of the headroom (in units) among the split levels
  // left; the final list's limit in samples holds for the whole pass.
  const long long headroom = std::max(0LL, budget.units - countBefore.units);
  const long long limit =
      countBefore.units + headroom / (long long)std::max<std::size_t>(1, splitLevelsLeft);
  std::vector<long long> units(kErrorBins, 0), samples(kErrorBins, 0);
  addLevelDeltas(d, next.voxels, budget.sampleUnit, kErrorBins, units, samples);
  d.cut = worstFirstCut(units, samples, d.count, limit, budget.samples);
  for (std::size_t j = 0; j < n; ++j) {
    if (group[j] >= d.cut) {
      d.split[j] = 1;
      ++d.splits;
      next.forEachChild(centres[j], radii[j], [&](std::size_t v) {
        next.inSet[v] = 1;
        if (next.ancestor[v] < 0 || anc[j] < next.ancestor[v]) next.ancestor[v] = anc[j];
      });
    } else {
      d.maxLeft = std::max(d.maxLeft, errors[j]);
      if (group[j] >= 0)
        ++d.capped;
      else
        d.maxBelow = std::max(d.maxBelow, errors[j]);
    }
  }
  d.vertices = compactFlags(next.inSet);
  d.ancestors.resize(d.vertices.size());
  for (std::size_t i = 0; i < d.vertices.size(); ++i) d.ancestors[i] = next.ancestor[d.vertices[i]];
  return d;
}

TopUp budgetTopUp(const Box& bounds, std::vector<BudgetLevel>& levels, BudgetCount count,
                  const BudgetLimits& budget) {
  TopUp t;
  t.toppedUp.assign(levels.size(), 0);
  if (budget.units <= 0 || count.units >= budget.units) return t;
  // The levels' histograms below their cuts: the capped candidates and the unmarked vertices.
  std::vector<long long> units(kErrorBins, 0), samples(kErrorBins, 0);
  for (const BudgetLevel& L : levels)
    addLevelDeltas(L.decision, L.grid.voxels, budget.sampleUnit, L.decision.cut, units, samples);
  BudgetCount after = count;
  t.cut = worstFirstCut(units, samples, after, budget.units, budget.samples);
  for (std::size_t k = 0; k < levels.size(); ++k) {
    BudgetLevel& L = levels[k];
    SplitDecision& d = L.decision;
    if (t.cut >= d.cut) continue;  // nothing of this level is topped up
    // The parents, in the result's order (their level's kept samples, by index).
    std::size_t rank = 0;
    for (std::size_t j = 0; j < d.split.size(); ++j) {
      if (d.split[j] && !L.grid.voxels) continue;  // split in the pass: not in the result
      const bool candidate = double(L.errors[j]) > d.threshold;
      if (!d.split[j] && candidate && errorBin(L.errors[j], d.threshold) >= t.cut) {
        if (!L.grid.voxels) t.removed.push_back(L.offset + rank);
        d.split[j] = 1;
        ++d.splits;
        --d.capped;
        ++t.toppedUp[k];
      }
      ++rank;
    }
    // The children: unmarked vertices whose worst marking candidate is topped up, ascending.
    const GridInfoBuffer g(bounds, L.grid);
    const float R = g.radius();
    for (std::size_t v = 0; v < d.vertexKey.size(); ++v) {
      const int key = int(d.vertexKey[v]) - 1;
      if (key < t.cut || key >= d.cut) continue;
      RadianceSample child;
      child.position = g.vertex(v);
      child.radius = R;
      child.level = int(k) + 1;
      t.children.push_back(child);
    }
    d.maxLeft = d.maxBelow;
    for (std::size_t j = 0; j < d.split.size(); ++j)
      if (!d.split[j]) d.maxLeft = std::max(d.maxLeft, L.errors[j]);
  }
  return t;
}

void applyTopUp(DynamicSamplingResult& result, const std::vector<BudgetLevel>& levels, TopUp&& t) {
  std::vector<std::uint8_t> drop(result.samples.size(), 0);
  for (std::size_t i : t.removed) drop[i] = 1;
  std::vector<RadianceSample> kept;
  kept.reserve(result.samples.size() - t.removed.size() + t.children.size());
  for (std::size_t i = 0; i < result.samples.size(); ++i)
    if (!drop[i]) kept.push_back(result.samples[i]);
  for (const RadianceSample& c : t.children) {
    kept.push_back(c);
    if (std::size_t(c.level) < result.levels.size()) ++result.levels[std::size_t(c.level)].samples;
  }
  result.samples = std::move(kept);
  for (std::size_t k = 0; k < levels.size() && k < result.levels.size(); ++k) {
    const SplitDecision& d = levels[k].decision;
    LevelStats& ls = result.levels[k];
    ls.split = d.splits;
    ls.capped = d.capped;
    ls.maxLeft = d.maxLeft;
    ls.toppedUp = t.toppedUp[k];
  }
}

namespace {

/// The top-up's children evaluated: with ∇S, but those of the voxel grid without (as the
/// voxel level itself), each group in one batch.
void evaluateTopUp(Frame& frame, const Scene& scene, RadianceEvaluator& evaluator,
                   const std::vector<LevelGrid>& grids, TopUp& t) {
  for (const bool voxels : {false, true}) {
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < t.children.size(); ++i) {
      const std::size_t l = std::size_t(t.children[i].level);
      if (l >= 1 && l <= grids.size() && grids[l - 1].voxels == voxels) idx.push_back(i);
    }
    if (idx.empty()) continue;
    std::vector<RadianceSample> batch(idx.size());
    for (std::size_t i = 0; i < idx.size(); ++i) batch[i] = t.children[idx[i]];
    evaluator.evaluate(frame, scene, batch, /*gradients=*/!voxels);
    for (std::size_t i = 0; i < idx.size(); ++i) t.children[idx[i]] = batch[i];
  }
}

/// One pass of recursive splitting on the host (dynamicSampling()): runSplitPass()'s steps. With
/// a budget the splits of each level are budgetedSplit()'s; without one every E > threshold
/// splits (the paper).
class HostSplitPass final : public SplitPassSteps {
 public:
  HostSplitPass(Frame& frame, const Scene& scene, std::vector<RadianceSample> initial,
                RadianceEvaluator& evaluator, const DynamicSamplingSettings& settings,
                const SplitPassPlan& plan)
      : frame_(frame),
        scene_(scene),
        density_(frame.hostDensity()),
        evaluator_(evaluator),
        settings_(settings),
        plan_(plan),
        current_(std::move(initial)),
        threshold_(settings.epsilon) {
    // τ of every level-0 sample; descendants index it through their ancestor.
    rootTau_.resize(current_.size());
    anc_.resize(current_.size());
    tbb::parallel_for(std::size_t(0), current_.size(), [&](std::size_t i) {
      rootTau_[i] = viewTransmittance(scene_, density_, current_[i].position, settings_.delta1);
      anc_[i] = std::int32_t(i);
    });
    // A towards the camera, the weights of the error of S = A ⊙ V (ErrorSpace::weightA).
    if (settings_.space.weightA)
      lightFactor_.emplace(scene_,
                           settings_.space.lampModel ? LampModel(scene_, density_) : LampModel());
  }

  void evaluate(std::size_t k, LevelEvaluation e) override {
    ls_ = LevelStats{};
    if (k > 0) {
      ls_.resolution = plan_.grids[k - 1].dims.x;
      ls_.voxels = plan_.grids[k - 1].voxels;
    }
    ls_.samples = (long long)current_.size();
    for (auto& s : current_) s.level = int(k);
    levelUnit_ = e == LevelEvaluation::FinalVoxels ? 1 : plan_.limits.sampleUnit;
    split_ = e == LevelEvaluation::Split && !current_.empty();
    // The voxel level's samples (final) need no ∇S: each reaches its own voxel centre only.
    if (!current_.empty())
      evaluator_.evaluate(frame_, scene_, current_, e != LevelEvaluation::FinalVoxels);
    if (split_) {
      errors(k);
    } else {
      // The finest level (or an empty one) is not split further.
      result_.samples.insert(result_.samples.end(), current_.begin(), current_.end());
      inResult_.units += (long long)current_.size() * levelUnit_;
      inResult_.samples += (long long)current_.size();
      current_.clear();
    }
  }

  void threshold() override {
    if (!split_) return;
    errorScale_ = settings_.relative ? relativeErrorScale(contributions_) : 0.0;
    threshold_ = settings_.relative ? settings_.epsilon * errorScale_ : settings_.epsilon;
  }

  void split(std::size_t k) override {
    if (!split_) return;
    ls_.threshold = threshold_;
    ls_.errorScale = errorScale_;
    if (plan_.budget > 0)
      budgetedLevel(k);
    else
      splitAll(k);
  }

  void endLevel(std::size_t) override { result_.levels.push_back(ls_); }

  void topUp() override {
    // The top-up: the budget the shares left unused, to the capped candidates, worst first.
    if (budgetLevels_.empty()) return;
    TopUp t = budgetTopUp(scene_.medium.bounds, budgetLevels_, inResult_, plan_.limits);
    evaluateTopUp(frame_, scene_, evaluator_, plan_.grids, t);
    applyTopUp(result_, budgetLevels_, std::move(t));
  }

  void finish() override {
    if (!result_.levels.empty()) result_.levels[0].budget = plan_.budget;
  }

  DynamicSamplingResult take(const std::vector<double>& ms) {
    for (std::size_t k = 0; k < result_.levels.size() && k < ms.size(); ++k)
      result_.levels[k].ms = ms[k];
    return std::move(result_);
  }

 private:
  /// Probes, E_j and (level 0, relative ε) the contributions of the current level.
  void errors(std::size_t k) {
    // Probes: S traced at x_j + R_j·d_i (one batched evaluation). A probe where the density is
    // zero adds nothing to Eq. 5 (its term is weighted by D), nor does one where the error is
    // weighted by A and A is zero (outside every spot cone), so only the others are traced.
    const int np = levelProbes(settings_, plan_.grids[k]);
    const std::size_t nProbes = current_.size() * std::size_t(np);
    const Vec3 eye = scene_.camera.position;
    std::vector<Vec3> probeAt(nProbes), probeA(lightFactor_ ? nProbes : 0);
    std::vector<float> probeD(nProbes);
    tbb::parallel_for(std::size_t(0), current_.size(), [&](std::size_t j) {
      Vec3 p[kMaxProbes];
      probePoints(current_[j], p, np);
      for (int i = 0; i < np; ++i) {
        const std::size_t q = np * j + i;
        probeAt[q] = p[i];
        probeD[q] = density_.sample(p[i]);
        if (lightFactor_)  // only where the term counts (A is large next to a lamp; D = 0: 0)
          probeA[q] = probeD[q] != 0.0f ? lightFactorTowardsEye(*lightFactor_, p[i], eye) : Vec3(0);
      }
    });
    std::vector<std::uint32_t> traced;  // indices of the probes whose term can be non-zero
    for (std::size_t q = 0; q < nProbes; ++q)
      if (probeD[q] != 0.0f && (!lightFactor_ || probeA[q] != Vec3(0.0f)))
        traced.push_back(std::uint32_t(q));
    std::vector<RadianceSample> probes(traced.size());
    for (std::size_t t = 0; t < traced.size(); ++t) probes[t].position = probeAt[traced[t]];
    evaluator_.evaluate(frame_, scene_, probes, /*gradients=*/false);
    std::vector<Vec3> probeS(nProbes, Vec3(0.0f));
    for (std::size_t t = 0; t < traced.size(); ++t) probeS[traced[t]] = probes[t].S;

    errors_.assign(current_.size(), 0.0f);
    contributions_.clear();
    if (k == 0 && settings_.relative) contributions_.resize(current_.size());
    tbb::parallel_for(std::size_t(0), current_.size(), [&](std::size_t j) {
      Vec3 S[kMaxProbes], A[kMaxProbes];
      float D[kMaxProbes];
      for (int i = 0; i < np; ++i) {
        S[i] = probeS[np * j + i];
        D[i] = probeD[np * j + i];
        if (lightFactor_) A[i] = probeA[np * j + i];
      }
      float tau = settings_.perSampleTau && k > 0
                      ? viewTransmittance(scene_, density_, current_[j].position, settings_.delta1)
                      : rootTau_[anc_[j]];
      if (settings_.visibleTau) {
        // τ of the most visible of the sample and its six axis probes (tau "visible").
        Vec3 pp[6];
        probePoints(current_[j], pp, 6);
        tau = mostVisibleTau(scene_, density_, tau, pp, 6, settings_.delta1);
      }
      errors_[j] = localShadingError(current_[j], S, D, tau, np, settings_.space,
                                     lightFactor_ ? A : nullptr, float(settings_.biasWeight));
      if (!contributions_.empty()) {
        const Vec3 a = lightFactor_
                           ? lightFactorTowardsEye(*lightFactor_, current_[j].position, eye)
                           : Vec3(1);
        contributions_[j] = sampleContribution(current_[j], density_.sample(current_[j].position),
                                               tau, settings_.space, lightFactor_ ? &a : nullptr);
      }
    });
    ls_.maxError = *std::max_element(errors_.begin(), errors_.end());
    ls_.p90Error = quantile(errors_, 0.9);
  }

  /// Budgeted: the level's splits worst first within its allotment (budgetedSplit()).
  void budgetedLevel(std::size_t k) {
    const std::size_t n = current_.size();
    std::vector<Vec3> centres(n);
    std::vector<float> radii(n);
    for (std::size_t j = 0; j < n; ++j) {
      centres[j] = current_[j].position;
      radii[j] = current_[j].radius;
    }
    const LevelGrid& next = plan_.grids[k];
    BudgetLevel& bl = budgetLevels_.emplace_back();
    bl.decision = budgetedSplit(
        scene_.medium.bounds, next, centres, radii, anc_, errors_, threshold_,
        {inResult_.units + (long long)n * levelUnit_, inResult_.samples + (long long)n},
        plan_.limits, plan_.levels() - k);
    const SplitDecision& d = bl.decision;
    bl.offset = result_.samples.size();
    bl.grid = next;
    for (std::size_t j = 0; j < n; ++j)
      if (!d.split[j] || next.voxels) {
        result_.samples.push_back(current_[j]);
        inResult_.units += levelUnit_;
        ++inResult_.samples;
      }
    ls_.split = d.splits;
    ls_.capped = d.capped;
    ls_.maxLeft = d.maxLeft;
    const GridInfoBuffer grid(scene_.medium.bounds, next);
    std::vector<RadianceSample> children(d.vertices.size());
    const float R = grid.radius();
    for (std::size_t i = 0; i < d.vertices.size(); ++i) {
      children[i].position = grid.vertex(d.vertices[i]);
      children[i].radius = R;
    }
    current_ = std::move(children);
    bl.centres = std::move(centres);
    bl.radii = std::move(radii);
    bl.anc = std::exchange(anc_, d.ancestors);
    bl.errors = std::move(errors_);
  }

  /// Unbudgeted: mark the vertices of G_{k+1} inside every sphere with E > threshold.
  void splitAll(std::size_t k) {
    const LevelGrid& nextGrid = plan_.grids[k];
    GridInfoBuffer next(scene_.medium.bounds, nextGrid);
    std::vector<std::uint8_t> split(current_.size());
    tbb::parallel_for(std::size_t(0), current_.size(), [&](std::size_t j) {
      split[j] = double(errors_[j]) > threshold_ ? 1 : 0;
      if (split[j]) next.markSphere(current_[j].position, current_[j].radius, anc_[j]);
    });
    for (std::size_t j = 0; j < current_.size(); ++j) {
      if (split[j]) {
        ++ls_.split;
        // The fallback keeps the sample: its cell's voxels are added, the sample still serves
        // the rest of its sphere.
        if (nextGrid.voxels) result_.samples.push_back(current_[j]);
      } else {
        result_.samples.push_back(current_[j]);
        ls_.maxLeft = std::max(ls_.maxLeft, errors_[j]);
      }
    }
    // Scan compaction of the grid information buffer into Q^{k+1}.
    const std::vector<std::uint32_t> verts = compactFlags(next.inSet);
    std::vector<RadianceSample> children(verts.size());
    std::vector<std::int32_t> childAnc(verts.size());
    const float R = next.radius();
    tbb::parallel_for(std::size_t(0), verts.size(), [&](std::size_t i) {
      children[i].position = next.vertex(verts[i]);
      children[i].radius = R;
      childAnc[i] = next.ancestor[verts[i]];
    });
    current_ = std::move(children);
    anc_ = std::move(childAnc);
  }

  Frame& frame_;
  const Scene& scene_;
  const DensityGrid& density_;
  RadianceEvaluator& evaluator_;
  const DynamicSamplingSettings& settings_;
  const SplitPassPlan& plan_;
  std::vector<RadianceSample> current_;  ///< the level's samples
  std::vector<std::int32_t> anc_;        ///< their level-0 ancestors
  std::vector<float> rootTau_;           ///< τ of every level-0 sample
  std::optional<LightFactor> lightFactor_;
  std::vector<float> errors_, contributions_;  ///< the level's E_j; level 0's contributions
  double threshold_, errorScale_ = 0.0;        ///< set on level 0
  LevelStats ls_;                              ///< the level's statistics
  long long levelUnit_ = 1;                    ///< a sample's weight in the budget's units
  bool split_ = false;                         ///< the level is split (not final, not empty)
  BudgetCount inResult_;  ///< the budget's count of the samples in the result so far
  std::vector<BudgetLevel> budgetLevels_;  ///< the split levels, for the top-up
  DynamicSamplingResult result_;
};

}  // namespace

DynamicSamplingResult dynamicSampling(Frame& frame, const Scene& scene,
                                      std::vector<RadianceSample> initial,
                                      RadianceEvaluator& evaluator,
                                      const DynamicSamplingSettings& settings) {
  const DynamicSamplingSettings s = forInitialSamples(settings, scene.medium.bounds, initial);
  const SplitPassPlan plan = splitPassPlan(s, initial.size());
  HostSplitPass pass(frame, scene, std::move(initial), evaluator, s, plan);
  const std::vector<double> ms = runSplitPass(pass, plan);
  return pass.take(ms);
}

DynamicSamplingResult dynamicSampling(const Scene& scene, const DensityGrid& density,
                                      std::vector<RadianceSample> initial,
                                      RadianceEvaluator& evaluator,
                                      const DynamicSamplingSettings& settings) {
  HostFrame frame(density);
  return dynamicSampling(frame, scene, std::move(initial), evaluator, settings);
}

void addDynamicSamplingStats(RenderStats& st, const DynamicSamplingResult& result,
                             const DynamicSamplingSettings& settings) {
  const std::vector<LevelStats>& levelStats = result.levels;
  std::vector<long long> perLevel = result.finalPerLevel;
  if (perLevel.empty()) {
    perLevel.assign(levelStats.size(), 0);
    for (const auto& s : result.samples)
      if (std::size_t(s.level) < perLevel.size()) ++perLevel[std::size_t(s.level)];
  }
  perLevel.resize(levelStats.size(), 0);
  Json levels = Json::array();
  for (std::size_t l = 0; l < levelStats.size(); ++l) {
    const LevelStats& ls = levelStats[l];
    levels.push_back({{"grid", ls.resolution},
                      {"evaluated", ls.samples},
                      {"split", ls.split},
                      {"kept", perLevel[l]},
                      {"max_error", ls.maxError},
                      {"p90_error", ls.p90Error},
                      {"capped", ls.capped},
                      {"topped_up", ls.toppedUp},
                      {"max_left", ls.maxLeft},
                      {"ms", ls.ms}});
    if (ls.voxels) levels.back()["fallback"] = true;
  }
  st.extra["samples_per_level"] = perLevel;
  st.extra["initial_samples"] = levelStats.empty() ? 0 : levelStats[0].samples;
  st.extra["levels"] = levels;
  st.extra["epsilon"] = settings.epsilon;
  st.extra["error"] = settings.relative ? "relative" : "absolute";
  st.extra["threshold"] = levelStats.empty() ? settings.epsilon : levelStats[0].threshold;
  if (settings.relative && !levelStats.empty()) st.extra["error_scale"] = levelStats[0].errorScale;
  if (settings.costShare > 0.0) {
    st.extra["budget_share"] = settings.costShare;  // the `budget` key: a share of per-voxel
    if (settings.perVoxelTraces > 0) st.extra["budget_voxels"] = settings.perVoxelTraces;
  }
  if (settings.maxSamples == kAutoBudget)
    st.extra["max_samples"] = "auto";
  else
    st.extra["max_samples"] = settings.maxSamples;
  const long long budget = levelStats.empty() ? 0 : levelStats[0].budget;
  if (budget > 0) {
    st.extra["budget"] = budget;
    st.extra["budget_runs"] = levelStats[0].budgetRuns;
    long long capped = 0;
    float maxLeft = 0.0f;
    for (const LevelStats& ls : levelStats) {
      capped += ls.capped;
      maxLeft = std::max(maxLeft, ls.maxLeft);
    }
    st.extra["capped"] = capped;
    const double threshold = levelStats[0].threshold;
    st.extra["error_left"] = threshold > 0.0 ? double(maxLeft) / threshold : 0.0;
  }
  st.extra["fallback"] = settings.voxelFallback;
  if (settings.biasWeight > 0.0) st.extra["bias_weight"] = settings.biasWeight;
  st.extra["split_rule"] = settings.splitCells ? "cell" : "sphere";
  st.extra["tau"] =
      settings.visibleTau ? "visible" : (settings.perSampleTau ? "sample" : "ancestor");
  st.extra["probes"] = settings.probes;
  st.extra["error_weight"] = settings.space.weightA ? "A" : "none";
}

/// Defaults of the extended dynamic sampling (render.paper false), chosen by the measurements
/// in docs/dynamic-sampling.md.
constexpr double kRelativeEpsilon = 0.05;
constexpr int kExtendedProbes = 40;
/// Every probe traces every light: by default a sample's probes trace at most this many light
/// segments (40 probes up to 4 lights, 26 with 5–6, never fewer than 14; docs/fidelity.md §13).
constexpr int kProbeLightTraces = 160;

static int defaultProbes(std::size_t lights) {
  for (int n : {kExtendedProbes, 26})
    if (std::size_t(n) * std::max<std::size_t>(1, lights) <= std::size_t(kProbeLightTraces))
      return n;
  return 14;
}

const std::vector<KeyDoc>& dynamicSamplingKeys() {
  static const std::vector<KeyDoc> keys = {
      {"epsilon", "number", "0.05 (relative); 1e-4 (absolute) with paper", "≥ 0",
       "split a sample when its error E_j (Eq. 5) is above epsilon · the mean R³|S|Dτ of the "
       "initial samples (relative), or, with paper, above epsilon itself (the paper's ε)",
       "0.5"},
      {"levels", "array of int",
       "[16, 32, 64]: those ≤ half the medium resolution; not with paper, only those finer "
       "than the initial samples, and half the medium resolution added where it is ≥ 1.5 × "
       "the last (e.g. [16, 32, 56] at 112³; docs/fidelity.md \"Population of scenes\")",
       "increasing, each 2…1024, finest ≤ half the medium resolution",
       "vertices per axis of the split grids G1, G2, …", "[2]"},
      {"tau", "string", "visible (ancestor with paper)",
       "ancestor, sample, visible (not with paper)",
       "τ to the viewer in Eq. 5: from the level-0 ancestor (paper), the sample itself, or the "
       "most visible of the ancestor's and the sample's six axis probes (a sample hidden behind "
       "an occluder whose sphere reaches the visible side)",
       R"("sample")"},
      {"probes", "int",
       "40 with up to 4 lights, 26 with 5–6, 14 with more (at most 160 light traces per "
       "sample: every probe traces every light; docs/fidelity.md §13); 6 with paper",
       "6, 14, 26, 40",
       "probe points per sample: Eq. 5's six, + 8 cube diagonals, + 12 edge diagonals, + 14 at "
       "R/2",
       "6"},
      {"max_samples", "int",
       "auto: 4 × the initial count, at most 8000, or more by budget (no cap with paper)",
       "≥ 0 (a non-integer is rounded down; 0 = no cap; not with paper)",
       "most samples in the final set: each level splits its largest errors first within an "
       "equal share of the budget left (one pass)",
       "100"},
      {"budget", "number", "0.75 (0 with max_samples given or with paper)",
       "0…1000 (not with paper)",
       "the samples' budget as a share of per-voxel's cost on the same scene, B = budget × "
       "per-voxel's voxels / (7 + probes) (a sample costs S, its six central differences and its "
       "probes; per-voxel one S per radiance voxel it traces: the occupied ones a light reaches, "
       "stat `budget_voxels`; every voxel with voxel_switch 0): the final set may grow to "
       "max(max_samples' auto rule, B); with max_samples given, to the smaller of the two (0 on "
       "either side: the "
       "other). The per-voxel fallback's voxels are paid at their cost, one S each (the pass "
       "may use B × (7 + probes) S evaluations), the final set at most 4 × B samples and at most "
       "max_samples where given",
       "1"},
      {"split", "string", R"("cell" ("sphere" with paper))", "cell, sphere (not with paper)",
       "what a split sample is replaced by: the vertices of the next grid in its cell (the cube "
       "of edge R around it: 8 when the grid doubles) or, the paper, every vertex inside its "
       "sphere (about 33)",
       R"("sphere")"},
      {"error_weight", "string",
       R"("radiance"; "transmittance" with factor_lights in scenes with directional lights only)",
       "radiance, transmittance (transmittance needs factor_lights)",
       "what E_j (Eq. 5) and the relative ε's scale measure: the source radiance S the image "
       "sees (with factor_lights the error of V weighted per probe by the lights' analytic "
       "unshadowed A = S / V there, docs/fidelity.md §12), or the samples' V = S / A itself",
       R"("transmittance")"},
      {"bias_weight", "number",
       "3 where a light is a point or spot light (0 with directional "
       "lights only, and with paper)",
       "0…100 (not with paper)",
       "weight k of the probes' signed error in Eq. 5: E_j uses mean D·|L̃ − L| + k·|mean "
       "D·(L̃ − L)|, so a sample whose probes all err the same way (a bias the image adds up: "
       "Taylor's tangents under a convex V on a dense sheet) splits at up to 1 + k times its "
       "error; 0 is Eq. 5 (docs/fidelity.md, \"The probes' signed bias in Eq. 5\")",
       "1"},
      {"fallback", "bool", "true (false with paper)", "true, false (not with paper)",
       "per-voxel fallback: the finest level is probed too (with fallback_probes), and where a "
       "cell of it still fails the error test S is evaluated directly at the voxels inside it "
       "(final samples that give the reconstruction exactly that value there)",
       "false"},
      {"fallback_probes", "int", "6", "6, 14, 26, 40 (at most probes are used; not with paper)",
       "probe points on the level the fallback follows (the finest of levels): probing it is "
       "what the fallback costs where nothing fails",
       "14"},
  };
  return keys;
}

/// A probe count key (`probes`, `fallback_probes`): one of the sets probePoints() knows.
static int probeCount(Params& p, const char* key, int def) {
  const long long n = p.integer(key, def);
  if (n != 6 && n != 14 && n != 26 && n != 40)
    p.fail(key, "value " + std::to_string(n) +
                    " is not allowed; allowed: 6 (Eq. 5: x ± R along X, Y, Z), 14 (+ cube "
                    "diagonals), 26 (+ edge diagonals), 40 (+ 14 at R/2)");
  return int(n);
}

DynamicSamplingSettings parseDynamicSampling(Params& p, const Scene& scene, bool paper,
                                             bool factorLights) {
  DynamicSamplingSettings s;
  // One threshold key: a fraction of the error scale, or with paper the paper's absolute ε.
  s.relative = !paper;
  s.epsilon = p.number("epsilon", paper ? 1e-4 : kRelativeEpsilon, Interval::atLeast(0));
  if (paper && p.has("max_samples"))
    p.fail("max_samples", "is an extension; it cannot be set with render.paper = true");
  // A number rather than an integer so that any non-negative value is valid (0: no cap).
  if (p.has("max_samples"))
    s.maxSamples =
        (long long)std::floor(std::min(p.number("max_samples", 0.0, Interval::atLeast(0)), 9e15));
  else {
    p.allow("max_samples");
    s.maxSamples = paper ? 0 : kAutoBudget;
  }
  if (paper && p.has("budget"))
    p.fail("budget", "is an extension; it cannot be set with render.paper = true");
  // The cost share: its default with the max_samples rule (auto), none beside an explicit count.
  s.costShare = p.number("budget", paper || p.has("max_samples") ? 0.0 : kBudgetCostShare,
                         Interval::closed(0.0, 1000.0));
  if (paper && p.has("bias_weight"))
    p.fail("bias_weight", "is an extension; it cannot be set with render.paper = true");
  // Where a point or spot light makes A singular (as error_weight's default below): 3.
  const bool singular = std::any_of(scene.lights.begin(), scene.lights.end(), [](const Light& l) {
    return l.type != Light::Type::Directional;
  });
  s.biasWeight = p.number("bias_weight", !paper && singular ? kSingularBiasWeight : 0.0,
                          Interval::closed(0.0, 100.0));
  if (paper && p.has("fallback"))
    p.fail("fallback", "is an extension; it cannot be set with render.paper = true");
  // On by default since issue 35 (docs/fidelity.md, "Population of scenes"): the worst scenes'
  // worst visibly wrong share halves for 9-13 % of the median time (two runs), with the finest
  // level probed at 6 points.
  s.voxelFallback = p.boolean("fallback", !paper);
  if (paper && p.has("fallback_probes"))
    p.fail("fallback_probes", "is an extension; it cannot be set with render.paper = true");
  s.fallbackProbes = probeCount(p, "fallback_probes", 6);
  s.voxelDims = scene.medium.resolution;
  const IVec3 res = scene.medium.resolution;
  const int finestAllowed = std::max(2, std::max(res.x, std::max(res.y, res.z)) / 2);
  if (p.has("levels")) {
    const Json& j = p.raw("levels");
    if (!j.is_array() || j.empty())
      p.fail("levels",
             "expected a non-empty array of increasing integers, got " + describeValue(j));
    s.levels.clear();
    for (const Json& v : j) {
      if (!v.is_number_integer() || v.get<int>() < 2 || v.get<int>() > 1024)
        p.fail("levels", "element " + describeValue(v) + " is not an integer in [2, 1024]");
      if (!s.levels.empty() && v.get<int>() <= s.levels.back())
        p.fail("levels", "must be increasing, got " + describeValue(j));
      s.levels.push_back(v.get<int>());
    }
  } else {
    p.allow("levels");
    s.autoLevels = !paper;
    s.finestLevel = finestAllowed;
    s.levels.clear();
    for (int l : {16, 32, 64})
      if (l <= finestAllowed) s.levels.push_back(l);
  }
  if (!s.levels.empty() && s.levels.back() > finestAllowed)
    p.fail("levels", "finest level " + std::to_string(s.levels.back()) +
                         " exceeds half the medium resolution (" + std::to_string(finestAllowed) +
                         ")");
  if (paper && p.has("split"))
    p.fail("split", "is an extension; it cannot be set with render.paper = true");
  s.splitCells = p.choice("split", {"sphere", "cell"}, paper ? "sphere" : "cell") == "cell";
  const std::string tau =
      p.choice("tau", {"ancestor", "sample", "visible"}, paper ? "ancestor" : "visible");
  if (paper && tau == "visible")
    p.fail("tau", "\"visible\" is an extension; it cannot be set with render.paper = true");
  s.perSampleTau = tau == "sample";
  s.visibleTau = tau == "visible";
  s.probes = probeCount(p, "probes", paper ? 6 : defaultProbes(scene.lights.size()));
  // The error of S = A ⊙ V (measured, docs/fidelity.md §12): a clear win where A has a point or
  // spot light's 1/d² and cone (glow masked 1.01 → 0.30 %, shaft_smoke 3.23 → 2.40 %); with
  // directional lights only A varies by the phase function alone and it never won (cloud,
  // thick_cloud slightly worse, thick_cloud_iso identical), so it is off there. Without
  // factor_lights the samples hold S and "radiance" is Eq. 5 itself.
  const bool onV =
      p.choice("error_weight", {"radiance", "transmittance"},
               factorLights && !singular ? "transmittance" : "radiance") == "transmittance";
  if (onV && !factorLights)
    p.fail("error_weight",
           "\"transmittance\" measures V = S / A of factor_lights; it needs factor_lights = true");
  s.space.weightA = factorLights && !onV;
  s.delta1 = scene.medium.voxelSize();
  return s;
}

namespace {

class CpuRefiner : public SampleRefiner {
 public:
  explicit CpuRefiner(DynamicSamplingSettings s) : s_(std::move(s)) {}
  DynamicSamplingResult refine(Frame& frame, const Scene& scene,
                               std::vector<RadianceSample> initial,
                               RadianceEvaluator& evaluator) override {
    return dynamicSampling(frame, scene, std::move(initial), evaluator, s_);
  }
  double tracesPerSample() const override { return 1.0 + s_.probes; }
  void setPerVoxelTraces(long long traces) override { s_.perVoxelTraces = traces; }
  void describe(RenderStats& stats, const DynamicSamplingResult& result) const override {
    addDynamicSamplingStats(stats, result, s_);
  }

 private:
  DynamicSamplingSettings s_;
};

}  // namespace

StageRegistry<RefinerMaker>& refiners() {
  static StageRegistry<RefinerMaker> r("sample refiner");
  return r;
}

DynamicSamplingSettings withPipeline(DynamicSamplingSettings ds, const PipelineSettings& ps) {
  ds.delta1 = ps.delta1;
  ds.space.bounds = taylorBounds(ps);
  ds.space.log = ps.logValues();
  ds.space.weightA = ds.space.weightA && ps.factorLights;
  ds.space.lampModel = ps.tracerSteps().lampModel;
  // The fallback's voxels are the radiance volume's, whose centres the reconstruction fills.
  if (ps.radianceResolution.x > 0) ds.voxelDims = ps.radianceResolution;
  return ds;
}

namespace {

/// What dynamic sampling plans (checkRenderPlan): ∇S at every sample, the probes of its first
/// level (only when there is a level to split into: `levels: []` traces none) and the grid
/// information buffer of its finest level.
StageWork dynamicSamplingWork(const Scene&, const PipelineSettings& ps) {
  const DynamicSamplingSettings& s = ps.refinerKeys.get<DynamicSamplingSettings>();
  StageWork w{.tracesGradients = true};
  if (s.levels.empty()) return w;
  w.probesPerSample = s.probes;
  w.probesKey = "probes";
  const double n = std::pow(double(s.levels.back()), 3.0);
  w.arrays.push_back({{"levels"},
                      "the grid buffer of level " + std::to_string(s.levels.back()) + "^3",
                      n * (sizeof(std::uint8_t) + sizeof(std::int32_t))});
  return w;
}

}  // namespace

void registerRefiners() {
  refiners().declare("dynamic",
                     {.keys = {{dynamicSamplingKeys,
                                [](Params& p, const Scene& scene, PipelineSettings& s) {
                                  s.refinerKeys.set(withPipeline(
                                      parseDynamicSampling(p, scene, s.paper, s.factorLights), s));
                                }}},
                      .work = dynamicSamplingWork});
  refiners().addVariant("dynamic", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<SampleRefiner>(
        new CpuRefiner(s.refinerKeys.get<DynamicSamplingSettings>()));
  });
}

}  // namespace scatterlab
