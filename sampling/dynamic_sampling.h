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
/// Scale of ε: E is (length³) × (source radiance) × (density), so ε depends on the scene's
/// units and light intensity. For a unit box, S of order 1 and initial radii ~0.1, E of a
/// badly reconstructed sample is of order 1e-4…1e-3; the stats report the largest E and the
/// 90th percentile per level to help choose ε.

#include <cstdint>
#include <vector>

#include "core/stages.h"
#include "core/stats.h"

namespace scatterlab {

struct DynamicSamplingSettings {
  double epsilon = 1e-4;                ///< split when E_j > epsilon
  std::vector<int> levels{16, 32, 64};  ///< vertices per axis of G1, G2, ... (increasing)
  bool perSampleTau = false;            ///< τ from each sample instead of its level-0 ancestor
  float delta1 = 0.0f;                  ///< step for tracing τ to the viewer (world units)
  /// Probe points per sample: 6 is Eq. 5 (x ± R along X, Y, Z). 14 and 26 add diagonal
  /// directions: an extension for shading boundaries that pass between the axis probes (a
  /// light shaft beside a large initial sphere), which Eq. 5 can miss.
  int probes = 6;
};

/// Grid information buffer of one level: vertices of G_k at the cell centres of a regular
/// N³ partition of the medium box (vertex (i,j,k) at min + (i + ½, j + ½, k + ½)·h), each with
/// its membership in Q^k and the level-0 sample whose τ it inherits. (The local shading errors
/// stay with the sample list of the level, which the scan compaction orders by vertex.)
struct GridInfoBuffer {
  Box bounds;
  IVec3 dims{0};
  Vec3 interval{0.0f};                 ///< h per axis
  std::vector<std::uint8_t> inSet;     ///< 1 when the vertex is in Q^k
  std::vector<std::int32_t> ancestor;  ///< index of the level-0 ancestor, or -1

  GridInfoBuffer(const Box& b, int resolution);
  Vec3 vertex(std::size_t linear) const;
  /// Valid radius of the level's samples: the grid interval (largest component of h).
  float radius() const { return std::max(interval.x, std::max(interval.y, interval.z)); }
  /// Marks every vertex strictly inside the sphere (c, R) as in the set, with ancestor
  /// min(existing, anc). Thread-safe.
  void markSphere(const Vec3& c, float R, std::int32_t anc);
};

struct LevelStats {
  int resolution = 0;     ///< 0 for the initial set
  long long samples = 0;  ///< |Q^k| evaluated at this level
  long long split = 0;    ///< of which split (E > ε)
  float maxError = 0.0f, p90Error = 0.0f;
  double ms = 0.0;  ///< wall time of the level (evaluation, error, split, scan)
};

/// The q-quantile of `v` (the element of rank ⌊q·n⌋, clamped to the last; 0 when empty):
/// LevelStats::p90Error of the CPU and GPU dynamic sampling, which must agree.
float quantile(std::vector<float> v, double q);

struct DynamicSamplingResult {
  std::vector<RadianceSample> samples;  ///< ∪_k Q^k minus the split ones; S and dS evaluated
  std::vector<LevelStats> levels;       ///< [0] = initial set, then one per grid level
};

/// E_j of Eq. 5 from the evaluated sample, the traced S at its six probes (order +X −X +Y −Y
/// +Z −Z), the density there, and τ.
/// Most probe points a sample can have.
inline constexpr int kMaxProbes = 26;

/// E_j of Eq. 5 from the evaluated sample, the traced S at its `count` probes (in the order of
/// probePoints), the density there, and τ. count = 6 is the paper's Eq. 5.
float localShadingError(const RadianceSample& s, const Vec3* probeS, const float* probeD, float tau,
                        int count = 6);

/// The probe points x_j + R_j·d of a sample: d = +X −X +Y −Y +Z −Z (the paper's six), then the
/// 8 cube diagonals, then the 12 edge diagonals (unit vectors). count is 6, 14 or 26.
void probePoints(const RadianceSample& s, Vec3* out, int count = 6);

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
};
using RefinerMaker =
    StageMaker<SampleRefiner, const DynamicSamplingSettings&, const PipelineSettings&>;
/// "dynamic": the paper's recursive splitting.
StageRegistry<RefinerMaker>& refiners();
/// Registers the CPU variant of "dynamic".
void registerRefiners();

/// Adds the dynamic-sampling facts to render stats (shared by the CPU and GPU `adaptive`):
/// samples_per_level (final samples per level), initial_samples, levels (per level: grid,
/// evaluated, split, kept, max_error, p90_error, ms), epsilon, tau, probes.
void addDynamicSamplingStats(RenderStats& stats, const std::vector<LevelStats>& levels,
                             const std::vector<RadianceSample>& samples,
                             const DynamicSamplingSettings& settings);

/// Reads the dynamic-sampling keys of the render object (table in dynamic_sampling.cpp):
/// epsilon, levels, tau, probes. delta1 is not read here (the pipeline's Δ1 is used; this
/// sets it to one voxel edge for callers without a pipeline).
DynamicSamplingSettings parseDynamicSampling(Params& render, const Scene& scene);

/// The key table of parseDynamicSampling (render keys of method `adaptive`).
const std::vector<KeyDoc>& dynamicSamplingKeys();

}  // namespace scatterlab
