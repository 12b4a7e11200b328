#pragma once
/// CPU reconstructions of the source-radiance volume from radiance samples (DESIGN.md §3,
/// stage "reconstruction"), registered as "gradient", "rbf", "nearest" and "per-voxel".
///
/// The three interpolating ones share one gather: the paper's slice splatting (Sec. 4) done
/// on the CPU. Each Z slice of the volume is one TBB task (it owns its output slice); a slice
/// visits only the samples whose valid sphere reaches it (binned once), and for each of them
/// only the voxel rows and the x-range inside the sphere, into per-thread accumulators that
/// are cleared only where they were touched. The normalisation is fused per row over the span
/// the spheres touched; the rest of the row is written as zero unless occupied. So the cost is
/// the sphere/voxel overlap plus a write of the output and one pass over the density rows
/// (bench/bench_interpolation.cpp BM_InterpGatherScaling, docs/benchmarks.md), not samples ×
/// voxels. Sums run in sample order, so results are deterministic; the gradient rows run 4 or
/// 8 voxels wide (gather_rows.h: AVX2 where the CPU has it, same operations).
///
/// Uncovered voxels: an occupied voxel (VoxelOccupancy: density non-zero in its trilinear
/// support) that no valid sphere contains is counted in ReconstructionStats::uncovered and
/// gets S of the nearest sample (Euclidean). The zeroth-order value is used, not the Taylor
/// estimate, because outside the valid sphere the first-order term is by definition not
/// trusted. With no samples at all these voxels stay zero (and are all counted).
/// Unoccupied, uncovered voxels are zero: the marcher never reads them.
/// Every result is clamped to S >= 0 per channel (a first-order estimate can undershoot near a
/// point light; negative source radiance is unphysical).

#include <optional>

#include "core/stages.h"

namespace scatterlab {

class LitReach;

enum class Interpolation {
  /// Paper Eq. 4: S(x) = Σ W_j(x)·(S_j + (x − x_j)·∇S_j) / Σ W_j(x) over {j : ‖x − x_j‖ < R_j},
  /// W_j(x) = R_j / ‖x − x_j‖. Singularity: ‖x − x_j‖ is clamped below at kSingularEps·R_j,
  /// so W_j <= 1e9; at x = x_j the sample's own value outweighs the others by that factor
  /// (for coincident samples, their average).
  Gradient,
  /// S_j of the closest sample whose valid sphere contains x (ties: the first in order).
  Nearest,
  /// The normalised RBF interpolation of Zhou et al. 2007 (see interpolation.cpp):
  /// S(x) = Σ w_j·exp(−‖x − x_j‖²/r_j²)·S_j / Σ w_j·exp(−‖x − x_j‖²/r_j²), r_j = R_j/3,
  /// over {j : ‖x − x_j‖ < R_j} (R_j = 3 r_j is the Gaussian's culling radius).
  Rbf,
};

/// Fills `out` (bounds and dims preset) from the samples. `weightSum`, when given (it is reset
/// to out's bounds and dims), receives the denominator at each voxel centre (Σ W_j for
/// Gradient, Σ w_j·B_j for Rbf, 1 where covered for Nearest). No GL context.
/// What the samples' S holds: the value itself (results clamped to >= 0), or its natural
/// logarithm (results exponentiated: PipelineSettings::logSpace).
enum class ValueSpace { Linear, Log };

/// `lit` (the volume holds V = S / A, which the march multiplies by A): a voxel it does not
/// reach within the voxel's half-diagonal is 0 and never uncovered, and a sample it does not
/// reach within R + that is left out (TracerSteps::reach: it was not traced).
ReconstructionStats interpolateSamples(Interpolation kind, const DensityGrid& density,
                                       std::span<const RadianceSample> samples, RadianceGrid& out,
                                       Grid3<float>* weightSum = nullptr,
                                       ValueSpace space = ValueSpace::Linear,
                                       float occlusionSigmaT = 0.0f,
                                       std::optional<TaylorBounds> bounds = std::nullopt,
                                       const LitReach* lit = nullptr);

/// Brute-force evaluation of the interpolation at one point, over all samples (no clamping,
/// no uncovered rule): the formulas above executed literally, for tests and probes.
struct PointEstimate {
  Vec3 value{0.0f};        ///< numerator / denominator (0 when nothing covers x)
  float weightSum = 0.0f;  ///< the denominator
  int covering = 0;        ///< samples whose valid sphere contains x
};
PointEstimate interpolateAt(Interpolation kind, const Vec3& x,
                            std::span<const RadianceSample> samples);

/// Registers the CPU variants of "gradient", "rbf", "nearest" and "per-voxel" (which takes no
/// samples and traces every occupied voxel with delta1) in reconstructions().
void registerReconstructions();

}  // namespace scatterlab
