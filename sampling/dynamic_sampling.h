#pragma once
/// Dynamic sampling (paper Sec. 5): the local shading error of each sample (Eq. 5) and
/// recursive splitting of samples with too large an error into the vertices of ever finer
/// regular grids, with a grid information buffer per level and scan compaction. CPU variant;
/// the data layout (one GridInfoBuffer per level, compaction by exclusive scan in ascending
/// vertex order) is the one the GPU variant uses, so the two can be compared sample for sample.
///
/// Local shading error of sample j (Eq. 5):
///   E_j = R_j³ · Σ_{i=1..6} |L̃(x_ij) − L(x_ij)| / 6 · D(x_ij) · τ_{x_j v}
/// with probes x_ij = x_j ± R_j·X, ±R_j·Y, ±R_j·Z; L̃ the single-sample Taylor estimate
/// S_j + (x_ij − x_j)·∇S_j; L the traced S at the probe; |·| the mean absolute difference over
/// the RGB channels; D the density volume at the probe (0 outside the box); τ the transmittance
/// from x_j to the camera position, traced with step Δ1 — taken from each sample's level-0
/// ancestor (the paper's setting) or, optionally, from the sample itself.
/// Scale of ε: E is (length³) × (source radiance) × (density), so an absolute ε (the paper's)
/// depends on the scene's units and light intensity. The default (extension) is a relative ε:
/// the threshold is ε × relativeErrorScale(), the mean R³·|S|·D·τ of the initial samples, so one
/// ε works on every scene. The stats report the largest E and the 90th percentile per level, and
/// the threshold used.
///
/// Sample budget (extension, issue 24): a most final count B, met in the one splitting pass
/// (budgetedSplit(); never a re-run). Splitting level k reveals the errors of level k + 1 only
/// once they are evaluated, but what a split costs is known before: the vertices of G_{k+1}
/// it marks (strictly inside its sphere, or with splitCells in its cell: forEachChild) that no
/// other split of the level marks (shared vertices count once), minus the sample itself (not on
/// the per-voxel fallback's grid, where the sample stays). Each split level splits its candidates
/// (E_j > threshold) worst first, in groups of nearly equal E (errorBin(): 1/64 of an octave,
/// 1.1 % of E), and stops at the first group that does not fit the level's allotment: a split
/// never goes to a smaller error while a larger one waits. A group's cost is exact, read from two
/// histograms over the groups (issue 33: the GPU decides the cut with the same histograms, in
/// one pass and without the host): the candidates per group, and G_{k+1}'s vertices per group
/// of the worst candidate that marks them; splitting every group from the worst down to g adds
/// the vertices of groups ≥ g and removes the candidates of groups ≥ g. (Until issue 33 the
/// order was sample by sample, ties by index; groups change which samples split only within the
/// last group's 1.1 % of E.) The allotment: the headroom left, B − count, shared equally by the
/// split levels still to come (level k of L split levels may use 1/(L − k) of it); what a level
/// does not use passes to the finer ones. A plain worst-first greedy (allotment 1 on every
/// level) spends the whole budget on the coarsest level, whose errors are the largest because
/// E ∝ R³, and leaves nothing for the edges that only the finer levels resolve
/// (docs/dynamic-sampling.md measured it 3× worse than a uniform threshold); equal shares keep
/// room for them without guessing the errors not yet seen. A finer level may need less than its
/// share (lamps32: 8 candidates on the last split level); what the pass leaves unused then goes
/// to the top-up (budgetTopUp()): after the last level the capped candidates of every split
/// level, worst group first across the levels, split while the count fits, their children
/// evaluated in one batch without probes (they stay final). So the pass evaluates each level
/// once, plus at most one batch of top-up children: never a re-run. Default budget
/// (render.max_samples absent): kBudgetPerInitial × the initial count, at most kBudgetCap, raised
/// where per-voxel is dear to a share of its cost (costShare, key `budget`, issue 35;
/// sampleBudget()); with the budget a cost, the count is in S evaluations, so the per-voxel
/// fallback's voxels are paid at their cost (BudgetLimits). The error left is reported: per level
/// the candidates left unsplit (LevelStats::capped) and the largest E of a sample left unsplit
/// (LevelStats::maxLeft; / threshold > 1: the budget stopped the refinement there). The finest
/// level is not probed, so its errors are not known (with voxelFallback the finest of `levels` is
/// probed, and the voxel level, exact at its voxels, is the one not probed).
///
/// Issue 24 (docs/fidelity.md §8): the allocation between levels was measured against other
/// shares (top-up as a share, shares growing per level, greedy) and kept; what bound the budget
/// on the smokes was the price of a split, which splitCells cuts from ~33 children to 8.

#include <cstdint>
#include <functional>
#include <vector>

#include "core/stages.h"
#include "core/stats.h"

namespace scatterlab {

struct DynamicSamplingSettings {
  /// Split when E_j > threshold, where threshold = epsilon (absolute, the paper's ε) or, with
  /// `relative`, epsilon · errorScale (errorScale: see relativeErrorScale()).
  double epsilon = 1e-4;
  /// ε is a fraction of the scene's error scale instead of an absolute E (extension).
  bool relative = false;
  std::vector<int> levels{16, 32, 64};  ///< vertices per axis of G1, G2, ... (increasing)
  /// The levels are the defaults (key `levels` absent, extension, issue 35): forInitialSamples()
  /// drops those no finer than the initial samples, which a split could not refine.
  bool autoLevels = false;
  int finestLevel = 0;        ///< the finest level allowed: half the medium's largest resolution
  bool perSampleTau = false;  ///< τ from each sample instead of its level-0 ancestor
  /// τ in Eq. 5 raised to the most visible of the six axis probes x_j ± R_j·(X, Y, Z) (tau
  /// "visible", extension, issue 24): a sample behind a thin dense occluder (τ ≈ 0) whose
  /// sphere reaches through it to the visible side is weighted by what its sphere shows, not by
  /// its hidden centre, so its error there gets it split. Also used for the contribution of the
  /// relative ε's scale. Six view-transmittance traces per probed sample.
  bool visibleTau = false;
  float delta1 = 0.0f;  ///< step for tracing τ to the viewer (world units)
  /// Probe points per sample: 6 is Eq. 5 (x ± R along X, Y, Z). 14 and 26 add diagonal
  /// directions at distance R, 40 also the 6 axis and 8 diagonal directions at R/2: extensions
  /// for shading boundaries that pass between the axis probes (a light shaft beside a large
  /// initial sphere, or through its inside), which Eq. 5 can miss.
  int probes = 6;
  /// Weight k of the probes' signed error in E_j (key `bias_weight`, extension; 0: Eq. 5):
  /// see localShadingError().
  double biasWeight = 0.0;
  /// Most samples in the final set (0: no cap; kAutoBudget: sampleBudget() of the initial
  /// count): see budgetedSplit().
  long long maxSamples = 0;
  /// The budget as a cost (extension, issue 35; key `budget`; 0: none; default kBudgetCostShare):
  /// the final samples may cost costShare × what per-voxel's radiance stage costs on the same
  /// scene, counted in S evaluations (each traces every light): per-voxel evaluates S once per
  /// radiance voxel it traces (perVoxelTraces: the occupied ones a light reaches; where not
  /// counted, every voxel of voxelDims), a sample of dynamic sampling 1 + 6 (its ∇S by central
  /// differences) + probes times. So the most final samples are costShare · voxels / (7 + probes)
  /// (sampleBudget()): many on a large volume, where per-voxel is dear, few on a small one, and
  /// fewer the more probes each sample has. How it combines with maxSamples: sampleBudget();
  /// how the fallback's voxels count against it: BudgetLimits.
  double costShare = 0.0;
  /// Per-voxel fallback (extension, issue 24; key `fallback`): after `levels` one more split
  /// grid, the voxels of the radiance volume (voxelDims per axis). The finest of `levels` is then
  /// probed like the others, and a cell of it that fails the error test is replaced by S
  /// evaluated directly at the voxel centres inside its sphere: final samples of radius ½ the
  /// smallest voxel edge, so each reaches only its own voxel centre, where its weight R/‖x − x_j‖
  /// (clamped at a tiny ‖·‖) outweighs every other sample's and the reconstruction returns that
  /// S, the per-voxel value. They carry no ∇S (never used there; saves the six central
  /// differences per sample).
  bool voxelFallback = false;
  /// Probe points of the level the fallback follows (the finest of `levels`, probed only for
  /// the fallback; key `fallback_probes`): levelProbes().
  int fallbackProbes = 6;
  IVec3 voxelDims{0};  ///< the fallback grid (the radiance volume's dims; withPipeline())
  /// Per-voxel's S evaluations on the scene being refined (the occupied radiance voxels some
  /// light reaches; SampleRefiner::setPerVoxelTraces(), from the pipeline's occupancy count),
  /// the unit of the cost budget (costShare); 0: unknown, every voxel of voxelDims counts.
  long long perVoxelTraces = 0;
  /// Split into the cell (extension, key `split`: "cell"): a split sample is replaced by the
  /// vertices of G_{k+1} in its cell, the cube of edge R_j centred on it (for a cubic grid the
  /// cell of the partition: 8 children when the next grid is twice as fine), instead of every
  /// vertex inside its sphere (the paper: about 33). The cells of the children tile the
  /// parent's, and each child's sphere (R = h_{k+1}) covers its own cell; the rest of the
  /// parent's sphere is its neighbours'. A split costs 4× fewer samples, so a budget splits 4×
  /// more of them (docs/fidelity.md §8).
  bool splitCells = false;
  /// How the error compares values (set from the pipeline, not a key): see ErrorSpace.
  struct ErrorSpace {
    /// Taylor estimates clamped as the reconstruction clamps them (boundedTaylor).
    std::optional<TaylorBounds> bounds;
    /// The samples hold ln V: E_j and the contribution are measured on V = exp(·), what the
    /// image sees, not on ln V (whose errors are largest where V is too dark to matter).
    bool log = false;
    /// The samples hold V = S / A (factor_lights): E_j and the contribution are measured on
    /// S = A ⊙ V, what the image sees (key `error_weight` "radiance", issue 24, docs/fidelity.md
    /// §12): each probe's |Ṽ − V| (after exp in log space) is multiplied per RGB channel by A at
    /// the probe, the contribution's V by A at the sample, A = LightFactor towards the camera.
    /// Off: measured on V itself ("transmittance"; what the error was before).
    bool weightA = false;
    /// With weightA: A includes the near-lamp model (PipelineSettings::lampModel), as the
    /// march's A does.
    bool lampModel = false;
  } space;
};

/// Grid information buffer of one level: vertices of G_k at the cell centres of a regular
/// N³ partition of the medium box (vertex (i,j,k) at min + (i + ½, j + ½, k + ½)·h), each with
/// its membership in Q^k and the level-0 sample whose τ it inherits. (The local shading errors
/// stay with the sample list of the level, which the scan compaction orders by vertex.)
/// A split grid: `dims` vertices per axis; `voxels`: the per-voxel fallback's grid (see
/// DynamicSamplingSettings::voxelFallback), whose samples are final, without ∇S, and reach only
/// their own voxel centre.
struct LevelGrid {
  IVec3 dims{0};
  bool voxels = false;
  bool cells = false;  ///< a split marks the vertices in the cell, not the sphere (splitCells)
};

/// The split grids G1, G2, … of `s`: one cubic grid per entry of `levels`, then with
/// voxelFallback the voxel grid.
std::vector<LevelGrid> levelGrids(const DynamicSamplingSettings& s);

/// Probe points of the samples of a level whose splits go to `next`: `probes`, but at most
/// fallbackProbes where `next` is the per-voxel fallback's voxel grid. Probing that level is
/// all the fallback costs where nothing fails (issue 35's population: 8 → 63 ms of 113 on a
/// cloud at 40 probes), and its samples are 2 voxels apart, where Eq. 5's six see what 40 do.
int levelProbes(const DynamicSamplingSettings& s, const LevelGrid& next);

/// The settings for one pass over `initial` (CPU and GPU alike): with autoLevels, the levels
/// whose grid radius (box's largest extent / N) is not below the initial samples' largest radius
/// are dropped. A split marks the vertices of the next grid in the sample's cell (or sphere); a
/// grid no finer than the sample has at most one there, so the split would replace the sample by
/// one of the same size, or by none. That happens where the initial samples are fine: the grid
/// sampler places its 2000 samples in the occupied cells only, so a sparse medium (thin wisps,
/// a narrow plume in a large box) gets initial samples finer than G1 = 16 and G2 = 32, and every
/// split there ended in nothing (issue 35's population: wisps 20-54 % against per-voxel's 2-10 %).
/// Then, where the finest level allowed (finestLevel, half the medium's resolution) is at least
/// 1.5 × the last level kept (or, with none kept, than the initial samples' own N = extent / R),
/// it is added as one more level: on a 112³ volume [16, 32] → [16, 32, 56], so a thin sheet or
/// wisp is refined to 2 voxels instead of 3.5 (issue 35: "the finest level is too coarse for
/// thin structure"). Without levels, the pass keeps the initial samples (and with
/// voxelFallback goes straight to the voxels).
DynamicSamplingSettings forInitialSamples(DynamicSamplingSettings s, const Box& bounds,
                                          const std::vector<RadianceSample>& initial);

struct GridInfoBuffer {
  Box bounds;
  IVec3 dims{0};
  Vec3 interval{0.0f};                 ///< h per axis
  bool voxels = false;                 ///< the per-voxel fallback's grid (LevelGrid::voxels)
  bool cells = false;                  ///< splits mark cells (LevelGrid::cells)
  std::vector<std::uint8_t> inSet;     ///< 1 when the vertex is in Q^k
  std::vector<std::int32_t> ancestor;  ///< index of the level-0 ancestor, or -1

  GridInfoBuffer(const Box& b, int resolution);
  GridInfoBuffer(const Box& b, const LevelGrid& grid);
  Vec3 vertex(std::size_t linear) const;
  /// Valid radius of the level's samples: the grid interval (largest component of h); on the
  /// voxel grid ½ the smallest voxel edge (a sample reaches its own voxel centre only).
  float radius() const {
    if (voxels) return 0.5f * std::min(interval.x, std::min(interval.y, interval.z));
    return std::max(interval.x, std::max(interval.y, interval.z));
  }
  std::size_t vertexCount() const { return std::size_t(dims.x) * dims.y * dims.z; }
  /// Marks every vertex strictly inside the sphere (c, R) (on the voxel grid: inside the cell,
  /// forEachChild) as in the set, with ancestor min(existing, anc). Thread-safe.
  void markSphere(const Vec3& c, float R, std::int32_t anc);
  /// Calls f(linear vertex index) for every vertex strictly inside the sphere (c, R), the
  /// vertices markSphere() marks, in ascending k, j, i.
  template <class F>
  void forEachInSphere(const Vec3& c, float R, F&& f) const {
    const IVec3 lo = glm::max(IVec3(glm::ceil((c - R - bounds.min) / interval - 0.5f)), IVec3(0));
    const IVec3 hi = glm::min(IVec3(glm::floor((c + R - bounds.min) / interval - 0.5f)), dims - 1);
    const float R2 = R * R;
    for (int k = lo.z; k <= hi.z; ++k)
      for (int j = lo.y; j <= hi.y; ++j)
        for (int i = lo.x; i <= hi.x; ++i) {
          const Vec3 q = bounds.min + (Vec3(i, j, k) + 0.5f) * interval;
          const Vec3 d = q - c;
          if (glm::dot(d, d) >= R2) continue;
          f((std::size_t(k) * dims.y + j) * dims.x + i);
        }
  }
  /// Calls f(linear vertex index) for every vertex in the cube of edge R centred on c, half
  /// open per axis ([c − R/2, c + R/2)): the cell of a sample of a cubic grid (R = its interval),
  /// which the cells of the level tile. The voxels the per-voxel fallback evaluates.
  template <class F>
  void forEachInCell(const Vec3& c, float R, F&& f) const {
    const Vec3 a = c - 0.5f * R, b = c + 0.5f * R;
    const IVec3 lo = glm::max(IVec3(glm::floor((a - bounds.min) / interval - 0.5f)), IVec3(0));
    const IVec3 hi = glm::min(IVec3(glm::ceil((b - bounds.min) / interval - 0.5f)), dims - 1);
    for (int k = lo.z; k <= hi.z; ++k)
      for (int j = lo.y; j <= hi.y; ++j)
        for (int i = lo.x; i <= hi.x; ++i) {
          const Vec3 q = bounds.min + (Vec3(i, j, k) + 0.5f) * interval;
          if (q.x < a.x || q.y < a.y || q.z < a.z || !(q.x < b.x) || !(q.y < b.y) || !(q.z < b.z))
            continue;
          f((std::size_t(k) * dims.y + j) * dims.x + i);
        }
  }
  /// The vertices a split of the sample (c, R) marks: inside its sphere (forEachInSphere, the
  /// paper), or inside its cell (forEachInCell: with `cells`, and always on the voxel grid, where
  /// the sample stays and the voxels are added).
  template <class F>
  void forEachChild(const Vec3& c, float R, F&& f) const {
    if (voxels || cells)
      forEachInCell(c, R, std::forward<F>(f));
    else
      forEachInSphere(c, R, std::forward<F>(f));
  }
};

struct LevelStats {
  int resolution = 0;     ///< 0 for the initial set (the voxel grid: its x dims)
  bool voxels = false;    ///< the per-voxel fallback's level
  long long samples = 0;  ///< |Q^k| evaluated at this level
  long long split = 0;    ///< of which split (E > threshold)
  float maxError = 0.0f, p90Error = 0.0f;
  double threshold = 0.0;   ///< the absolute threshold E_j was compared with (0: final level)
  double errorScale = 0.0;  ///< relativeErrorScale() of the initial set (relative ε; else 0)
  int budgetRuns = 1;       ///< level 0: splitting passes run (always 1: the budget is one pass)
  long long capped = 0;     ///< candidates (E > threshold) left unsplit by the sample budget
  long long toppedUp = 0;   ///< of the splits, those made by the budget's top-up (budgetTopUp)
  float maxLeft = 0.0f;     ///< largest E of a sample of this level left unsplit (0: final level)
  long long budget = 0;     ///< level 0: the sample budget applied (0: none)
  double ms = 0.0;          ///< wall time of the level (evaluation, error, split, scan)
};

/// The q-quantile of `v` (the element of rank ⌊q·n⌋, clamped to the last; 0 when empty):
/// LevelStats::p90Error of the CPU and GPU dynamic sampling, which must agree.
float quantile(std::vector<float> v, double q);

struct DynamicSamplingResult {
  std::vector<RadianceSample> samples = {};  ///< ∪_k Q^k minus the split ones; S and dS evaluated
  std::vector<LevelStats> levels = {};       ///< [0] = initial set, then one per grid level
  /// The final samples stay on the device (a resident GPU pass, issue 33): `samples` and
  /// `levels` are empty; the backend reports them after the frame.
  bool onDevice = false;
  /// Final samples per level where `samples` does not hold them (a GPU pass read without its
  /// samples); empty: counted from `samples`.
  std::vector<long long> finalPerLevel = {};
};

/// Contribution of one sample to the image, in the units of E_j (Eq. 5 with the error replaced
/// by S itself): R_j³ · mean_RGB |S_j| · D(x_j) · τ_j. `a` (ErrorSpace::weightA; null: none):
/// A at the sample, multiplying |S_j| (exp(S_j) in log space) per channel: the S = A ⊙ V the
/// image sees.
float sampleContribution(const RadianceSample& s, float density, float tau,
                         const DynamicSamplingSettings::ErrorSpace& space = {},
                         const Vec3* a = nullptr);

/// The error scale of a relative ε: the mean sampleContribution() of the initial samples,
/// summed in index order in double (so the CPU and GPU variants agree to float rounding). With
/// it E_j / scale is scale-free: it does not change when the scene is scaled in size, the
/// lights in intensity, or the initial count (R³ ∝ 1/N cancels).
double relativeErrorScale(const std::vector<float>& contributions);

/// Most probe points a sample can have.
inline constexpr int kMaxProbes = 40;
/// Probes summed together before the groups' sums are added (localShadingError): the GPU's probe
/// pass sums one group per workgroup row set (gpu/shaders/volume_tracer.comp.glsl, SL_PROBES),
/// and both sum in this order so that they agree to rounding. Eq. 5's six probes are one group,
/// summed as the paper's sum.
inline constexpr int kProbeGroup = 8;

/// The probe offsets of a unit sphere at the origin, in probePoints() order: the 6 axis
/// directions (Eq. 5), 8 cube diagonals, 12 edge diagonals (unit length), then the 6 axis and 8
/// cube-diagonal directions at length ½.
const Vec3* probeOffsets();

/// E_j of Eq. 5 from the evaluated sample, the traced S at its `count` probes (in the order of
/// probePoints), the density there, and τ. count = 6 is the paper's Eq. 5. The mean is over
/// the probes (Eq. 5's Σ/n), summed in groups of kProbeGroup. `space`: the Taylor estimate is
/// clamped to its bounds, and in log space both sides are exponentiated before they are compared
/// (extensions; the default is the paper's Eq. 5). `probeA` (ErrorSpace::weightA; null: none):
/// A at each probe (lightFactorTowardsEye()), multiplying the probe's |L̃ − L| per RGB channel
/// before the channel mean: the error of S = A ⊙ V when the samples hold V. `biasWeight` k
/// (key `bias_weight`, extension; 0: Eq. 5): the mean becomes mean D·|L̃ − L| + k·|mean
/// D·(L̃ − L)| — the signed errors summed in the same groups — so a sample whose probes all err
/// the same way (a Taylor tangent under a convex V: a bias the image adds up) counts up to
/// (1 + k)× Eq. 5's error, one whose errors cancel as before.
float localShadingError(const RadianceSample& s, const Vec3* probeS, const float* probeD, float tau,
                        int count = 6, const DynamicSamplingSettings::ErrorSpace& space = {},
                        const Vec3* probeA = nullptr, float biasWeight = 0.0f);

class LightFactor;

/// A(p, ω) of `A` with ω the unit direction from p to the camera at `eye` ((0, 0, 1) at the eye
/// itself): the direction the volume tracer evaluates V in (cpu/radiance_evaluator.cpp), so A ⊙
/// V is the S of the image there. The weights of ErrorSpace::weightA.
Vec3 lightFactorTowardsEye(const LightFactor& A, const Vec3& p, const Vec3& eye);

/// τ of tau "visible": the largest of `tau` and the transmittances exp(−σt·∫D) from each of the
/// n `points` to the camera (opticalDepth(density, p, camera, delta1)), with less work than n
/// whole marches: a point's march stops once its optical depth passes the smallest one found so
/// far (and the depth of `tau`), with 1e-4 of margin — its transmittance is then below the
/// largest and cannot be the result. The marches that finish sum the same steps in the same order
/// as opticalDepth, so the result is that of the n whole marches bit for bit.
float mostVisibleTau(const Scene& scene, const DensityGrid& density, float tau, const Vec3* points,
                     int n, float delta1);

/// The probe points x_j + R_j·d of a sample, d = probeOffsets()[0 … count): +X −X +Y −Y +Z −Z
/// (the paper's six), then the 8 cube diagonals, the 12 edge diagonals, and the inner shell at
/// R/2. count is 6, 14, 26 or 40.
void probePoints(const RadianceSample& s, Vec3* out, int count = 6);

/// max_samples absent (extended defaults): the budget is sampleBudget() of the initial count.
inline constexpr long long kAutoBudget = -1;
/// Default budget: this many final samples per initial sample ...
inline constexpr long long kBudgetPerInitial = 4;
/// ... and at most this many (issue 24: ≤ 8000 samples on every scene at defaults).
inline constexpr long long kBudgetCap = 8000;

/// Default of the cost share (key `budget`, issue 35): chosen on the population of scenes
/// (docs/fidelity.md, "Population of scenes"; 0.5 until V replaced ln V for adaptive, then
/// 0.75: "The budget re-checked with V").
inline constexpr double kBudgetCostShare = 0.75;

/// Default of `bias_weight` where the scene has a point or spot light (0 with directional lights
/// only, and with paper): chosen on the population (docs/fidelity.md, "The probes' signed bias
/// made a default where a light is singular"). On the 76 dynamically sampled scenes with such a
/// light the error misses went 7 → 0 and the median error 0.27 → 0.15 % for +14 % of their
/// median time; on the sunlit clouds it doubled the samples for one scene's gain.
inline constexpr double kSingularBiasWeight = 3.0;

/// The budget applied to `initialCount` initial samples (0: none). The cost cap C =
/// costShare · voxels / (7 + probes) when costShare > 0 (at least 1), voxels being per-voxel's
/// traces (perVoxelTraces, else the whole voxelDims grid). For kAutoBudget
/// max(min(kBudgetPerInitial · initialCount, kBudgetCap), C): the count rule's floor, raised where
/// per-voxel is dear; else the smaller of maxSamples and C, where one of them is 0 the other.
long long sampleBudget(const DynamicSamplingSettings& settings, std::size_t initialCount);

/// With the budget a cost, the final list holds at most this many × the budget's samples (see
/// BudgetLimits::samples; smoke.json at the defaults: 3.6×).
inline constexpr long long kFinalListPerBudget = 4;

/// A budget of B samples as the pass applies it (issue 35 item 3: the fallback inside the same
/// cost budget). Where the budget is a cost (costShare > 0) its unit is an S evaluation: a
/// sample weighs sampleUnit = 7 + probes (S, its six differences and its probes: what
/// sampleBudget()'s cost cap counts per sample) and a voxel of the per-voxel fallback 1 (one S,
/// no ∇S, no probes), so the fallback is paid at its cost, not as a sample, and `units` = B ×
/// sampleUnit. As each voxel is still a record of the final list, the list is also held to
/// `samples` = kFinalListPerBudget × B (the GPU's final-list capacity), and to max_samples where
/// the user gave one. With a count cap (max_samples alone) every final sample weighs 1 and both
/// limits are B. Zero: no budget.
struct BudgetLimits {
  long long units = 0;       ///< the most units the pass may use
  long long sampleUnit = 1;  ///< a sample's weight in units (a fallback voxel's: 1)
  long long samples = 0;     ///< the most samples in the final list
};
BudgetLimits budgetLimits(const DynamicSamplingSettings& settings, long long budget);

/// The budget's running count: units (BudgetLimits) and samples.
struct BudgetCount {
  long long units = 0;
  long long samples = 0;
};

/// The group of an error E > threshold for the budget's worst-first order (see the header
/// comment): its float's bits above the lowest kErrorBinShift (the exponent and 6 mantissa bits:
/// 1/64 of an octave) counted from the threshold's, at most kErrorBins − 1 (64 octaves above the
/// threshold; core/stages.h). Integer arithmetic on the float bits: the GPU computes the same
/// groups (dynamic_groups.glsl).
int errorBin(float e, double threshold);

/// The split decisions of one level under a budget (see the header comment): which samples
/// split, and the vertices of G_{k+1} they mark (ascending, as the scan compaction orders them)
/// with their level-0 ancestors (the smallest among the marking spheres, as markSphere()).
struct SplitDecision {
  std::vector<std::uint8_t> split;      ///< per sample of level k
  std::vector<std::uint32_t> vertices;  ///< linear indices of G_{k+1}, ascending
  std::vector<std::int32_t> ancestors;  ///< per vertex
  BudgetCount count;                    ///< final count after these splits (see countBefore)
  long long splits = 0, capped = 0;     ///< split; candidates left unsplit by the allotment
  float maxLeft = 0.0f;                 ///< largest E of a sample left unsplit
  float maxBelow = 0.0f;                ///< largest E of a non-candidate (E <= threshold)
  double threshold = 0.0;  ///< the absolute threshold the groups count from (errorBin())
  /// The lowest group split (kErrorBins: none): candidates of groups >= cut split.
  int cut = kErrorBins;
  /// Per group: the candidates (none on the fallback's grid, where a split keeps its sample),
  /// and the vertices of G_{k+1} whose worst marking candidate is of that group.
  std::vector<std::uint32_t> candidates, vertexGroups;
  /// Per vertex of G_{k+1}: 1 + the group of its worst marking candidate (0: none marks it).
  /// Marked by the splits: vertexKey − 1 >= cut.
  std::vector<std::uint32_t> vertexKey;
};

/// One split level as the top-up reads it: its decision, its samples, and where its unsplit
/// samples start in the result (levels are appended in order, each in index order).
struct BudgetLevel {
  SplitDecision decision;
  std::vector<Vec3> centres;
  std::vector<float> radii;
  std::vector<std::int32_t> anc;
  std::vector<float> errors;
  LevelGrid grid;          ///< G_{k+1}
  std::size_t offset = 0;  ///< index in DynamicSamplingResult::samples of its first kept sample
};

/// The top-up of a budgeted pass: the budget a level's share left unused (a finer level needed
/// fewer splits than its share) goes, after the last level, to the capped candidates of every
/// split level, worst group first across the levels (the levels' histograms below their cuts,
/// summed), each group while the count fits the budget, stopping at the first that does not.
/// Their children (the vertices of G_{k+1} no split of the pass marked, whose worst marking
/// candidate is topped up) are evaluated once, with ∇S and no probes (they are final), and
/// appended level by level, each in ascending vertex order.
struct TopUp {
  int cut = kErrorBins;                  ///< the lowest group topped up (kErrorBins: none)
  std::vector<std::size_t> removed;      ///< indices into the result of the split parents
  std::vector<RadianceSample> children;  ///< position, radius, level; S to be evaluated
  std::vector<long long> toppedUp;       ///< per split level: its splits made here
};

/// Decides the top-up (updates each level's decision: split, splits, capped, maxLeft).
/// `count`: the final count of the pass.
TopUp budgetTopUp(const Box& bounds, std::vector<BudgetLevel>& levels, BudgetCount count,
                  const BudgetLimits& budget);

/// Applies an evaluated top-up to the result: removes the parents, appends the children (in
/// the top-up's order), and updates the level stats (split, capped, toppedUp, maxLeft, and
/// the children's level's evaluated count).
void applyTopUp(DynamicSamplingResult& result, const std::vector<BudgetLevel>& levels,
                TopUp&& topUp);

/// The budgeted split of level k on the CPU (the GPU's dynamic_budget.comp.glsl decides the same
/// cut from the same histograms). centres/radii/anc/errors: the level's samples; `threshold`:
/// the absolute one; countBefore: kept samples of the coarser levels + this level's count;
/// budget; splitLevelsLeft: L − k (this level included): the level's allotment of units is an
/// equal share of the headroom left, the samples' limit the pass's. Deterministic.
SplitDecision budgetedSplit(const Box& bounds, const LevelGrid& grid,
                            const std::vector<Vec3>& centres, const std::vector<float>& radii,
                            const std::vector<std::int32_t>& anc, const std::vector<float>& errors,
                            double threshold, BudgetCount countBefore, const BudgetLimits& budget,
                            std::size_t splitLevelsLeft);

/// How level k of a splitting pass is evaluated: a split level (S and ∇S, then its probes and
/// errors E_j), a final grid level (S and ∇S), or the per-voxel fallback's voxels (final, S
/// only: each reaches its own voxel centre).
enum class LevelEvaluation { Split, Final, FinalVoxels };

/// What one splitting pass will do, decided once on the host for the CPU and the GPU alike: the
/// split grids G_1..G_L (levelGrids()), the budget (sampleBudget(); 0: none, every E > threshold
/// splits, the paper) and its limits.
struct SplitPassPlan {
  std::vector<LevelGrid> grids;
  long long budget = 0;
  BudgetLimits limits;
  std::size_t levels() const { return grids.size(); }
  /// Level L is the per-voxel fallback's voxels.
  bool fallback() const { return !grids.empty() && grids.back().voxels; }
  LevelEvaluation evaluation(std::size_t k) const;
};
SplitPassPlan splitPassPlan(const DynamicSamplingSettings& settings, std::size_t initialCount);

/// The steps of one splitting pass, on the host (dynamicSampling()) or as GPU passes
/// (gpu::dynamicSamplingGpu): runSplitPass() is the one level loop that calls them.
class SplitPassSteps {
 public:
  virtual ~SplitPassSteps() = default;
  /// Level k's samples evaluated as `e`; a split level's also probed, with their errors E_j.
  virtual void evaluate(std::size_t k, LevelEvaluation e) = 0;
  /// After level 0's errors: the error scale and the absolute threshold (relative ε).
  virtual void threshold() = 0;
  /// Level k's splits (with a budget: worst first within the level's allotment,
  /// budgetedSplit()), their children compacted into level k + 1's samples.
  virtual void split(std::size_t k) = 0;
  /// Level k is enqueued or done.
  virtual void endLevel(std::size_t /*k*/) {}
  /// With a budget and a split level: the top-up (budgetTopUp()).
  virtual void topUp() = 0;
  /// The final list: every level's kept samples, then the top-up's children.
  virtual void finish() = 0;
};

/// The level loop of a splitting pass (paper Sec. 5, Alg. 1): for k = 0..L evaluate level k,
/// and unless it is the finest, split it (on level 0 after the threshold); then the top-up and
/// the final list. Returns the host's milliseconds per level (level L's with the top-up and the
/// final list).
std::vector<double> runSplitPass(SplitPassSteps& steps, const SplitPassPlan& plan);

/// Runs recursive splitting from `initial` (positions and radii; level 0) over the frame's
/// density. `evaluator` (of the frame's backend) computes S and ∇S of the samples and S at the
/// probes. Deterministic: the same input gives the same samples in the same order (level by
/// level, ascending vertex index).
DynamicSamplingResult dynamicSampling(Frame& frame, const Scene& scene,
                                      std::vector<RadianceSample> initial,
                                      RadianceEvaluator& evaluator,
                                      const DynamicSamplingSettings& settings);

/// The same on a host density volume (copied into a HostFrame): for tests and benchmarks.
DynamicSamplingResult dynamicSampling(const Scene& scene, const DensityGrid& density,
                                      std::vector<RadianceSample> initial,
                                      RadianceEvaluator& evaluator,
                                      const DynamicSamplingSettings& settings);

/// Stage: dynamic sampling between the sampler and the reconstruction (method `adaptive`).
/// Returns the final sample set with S and ∇S evaluated. The CPU variant is dynamicSampling()
/// with the pipeline's evaluator; the GPU one (gpu/) runs its own passes.
class SampleRefiner {
 public:
  virtual ~SampleRefiner() = default;
  virtual DynamicSamplingResult refine(Frame& frame, const Scene& scene,
                                       std::vector<RadianceSample> initial,
                                       RadianceEvaluator& evaluator) = 0;
  /// The traces per initial sample that the whole-scene fallback (key `voxel_switch`) weighs
  /// against per-voxel's: 1 + probes, the first level's S and probes (its ∇S left out: the
  /// rule as chosen on the population, docs/fidelity.md).
  virtual double tracesPerSample() const = 0;
  /// What per-voxel would trace on the scene about to be refined (S evaluations: the occupied
  /// radiance voxels some light reaches; 0: unknown), the unit of the cost budget
  /// (DynamicSamplingSettings::perVoxelTraces). The pipeline sets it before each refine().
  virtual void setPerVoxelTraces(long long traces) = 0;
  /// Writes what refine() did into the stats (addDynamicSamplingStats with its settings); a
  /// result left on the device (DynamicSamplingResult::onDevice) is reported after the frame
  /// by the variant itself instead.
  virtual void describe(RenderStats& stats, const DynamicSamplingResult& result) const = 0;
};
/// A refiner's variants are built from the pipeline's settings; "dynamic"'s own keys are in
/// PipelineSettings::refinerKeys (a DynamicSamplingSettings, withPipeline() applied).
using RefinerMaker = StageMaker<SampleRefiner, const PipelineSettings&>;
/// "dynamic": the paper's recursive splitting.
StageRegistry<RefinerMaker>& refiners();
/// Declares "dynamic" (its keys: dynamicSamplingKeys()) and registers its CPU variant.
void registerRefiners();

/// `ds` as a pipeline runs it: delta1 is the pipeline's Δ1, and the error compares values as the
/// pipeline's samples hold them (Taylor bounds, log space). Both backends' variants use this.
DynamicSamplingSettings withPipeline(DynamicSamplingSettings ds, const PipelineSettings& ps);

/// Adds the dynamic-sampling facts to render stats (shared by the CPU and GPU `adaptive`):
/// samples_per_level (final samples per level), initial_samples, levels (per level: grid,
/// evaluated, split, capped, kept, max_error, p90_error, max_left, ms), epsilon, error
/// ("relative" or "absolute"), threshold (the absolute one used), error_scale, max_samples
/// (the key: "auto" or a number), and with a budget: budget (the one applied), budget_runs (1),
/// capped (candidates left unsplit, all levels), error_left (largest E left unsplit / threshold;
/// above 1 where the budget stopped the refinement); tau, probes.
void addDynamicSamplingStats(RenderStats& stats, const DynamicSamplingResult& result,
                             const DynamicSamplingSettings& settings);

/// Reads the dynamic-sampling keys of the render object (table in dynamic_sampling.cpp):
/// epsilon, levels, tau, probes, max_samples. With `paper` the paper's algorithm: epsilon is the
/// absolute ε (default 1e-4), probes default to Eq. 5's six, max_samples is an error (no
/// budget). Otherwise max_samples defaults to kAutoBudget. Otherwise
/// epsilon is relative (a fraction of relativeErrorScale(), default 0.05) and the defaults are
/// the measured best (docs/dynamic-sampling.md). delta1 is not read here (the pipeline's Δ1 is
/// used, withPipeline(); this sets it to one voxel edge for callers without a pipeline).
/// `factorLights` (PipelineSettings::factorLights): the samples hold V = S / A, and error_weight
/// "radiance" (default) weights E_j by A (ErrorSpace::weightA).
DynamicSamplingSettings parseDynamicSampling(Params& render, const Scene& scene, bool paper = false,
                                             bool factorLights = false);

/// The key table of parseDynamicSampling (render keys of method `adaptive`).
const std::vector<KeyDoc>& dynamicSamplingKeys();

}  // namespace scatterlab
