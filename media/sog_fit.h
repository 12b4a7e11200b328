#pragma once
/// Fitting the sum-of-Gaussians + residual-hash model to a dense grid (docs/media.md, "Fitting"):
///  1. box-filter the input down to at most `fitVoxels` cells (the working grid);
///  2. greedy placement on the working grid: put a Gaussian at the cell of largest residual,
///     pick its radius among candidates by the largest least-squares gain, subtract it;
///  3. refinement: `sweeps` passes over the Gaussians, each solving a 5-parameter non-linear
///     least-squares problem (centre, log radius, weight) against the residual of the others
///     with Eigen's Levenberg–Marquardt (analytic Jacobian);
///  4. a final linear least-squares solve of all weights on the full-resolution input (exact
///     normal equations, non-negative by active-set elimination);
///  5. residual F = D − D̃ at every input cell, quantised to `bits` bits with a common step and
///     kept where |F| > threshold·max(D); by default what a cell does not keep is diffused to
///     its neighbours so the model keeps the input's mass locally (SogResidualMode).

#include <functional>
#include <string>

#include "core/scene.h"
#include "media/sog.h"

namespace scatterlab {

/// How step 5 treats residuals below the threshold (docs/media.md, "Residual").
enum class SogResidualMode {
  /// Dropped (the original behaviour): thin smoke below threshold·max(D) is lost.
  Drop,
  /// Error diffusion: what a cell does not keep is carried to its neighbours, so the lattice
  /// sum of the model equals the input's (mass-preserving).
  Diffuse,
};

struct SogFitOptions {
  int gaussians = 512;       ///< number of Gaussians placed greedily (N)
  double threshold = 0.003;  ///< residual kept where |F| > threshold · max(D)
  int bits = 8;              ///< residual quantisation (8 or 16)
  SogResidualMode residual = SogResidualMode::Diffuse;
  std::int64_t fitVoxels = 48 * 48 * 48;  ///< working-grid budget for steps 2–3
  int sweeps = 2;                         ///< refinement passes (0: placement only)
  int lmMaxEvaluations = 40;              ///< function evaluations per local LM solve
  int lmMaxSamples = 4096;                ///< cells per local LM problem (strided subsample above)
  bool finalWeightSolve = true;
  /// Warm start (sequences): start from these Gaussians instead of greedy placement.
  const std::vector<GaussianBlob>* init = nullptr;
  /// Progress messages (may be empty).
  std::function<void(const std::string&)> log;
};

struct SogFitReport {
  int gaussians = 0;  ///< in the model (Gaussians with weight 0 are dropped)
  std::size_t hashEntries = 0;
  IVec3 fitDims{0};           ///< working-grid dims of steps 2–3
  double relL2Gaussians = 0;  ///< ‖D − D̃‖ / ‖D‖ on the input cells
  double relL2Model = 0;      ///< ‖D − max(0, D̃ + F)‖ / ‖D‖ on the input cells
  double relMassModel = 0;    ///< (Σ max(0, D̃ + F) − Σ D) / Σ D over the input cells
  double secondsPlacement = 0, secondsRefinement = 0, secondsWeights = 0, secondsResidual = 0;
  double secondsTotal = 0;
};

/// Fits `input` (its cell centres are the samples; its box becomes the residual lattice).
/// Throws ConfigError on bad options, LimitError when the input is empty (all zero).
SogModel fitSog(const DensityGrid& input, const SogFitOptions& options,
                SogFitReport* report = nullptr);

/// Settings of fit's image-space check (docs/media.md, "Image-space check").
struct SogCheckView {
  int width = 160, height = 120;
  /// Optical depth τ̄ the extinction is chosen for: σt = τ̄ / mean of the column integrals
  /// ∫D dz over the columns that hold any density, so thin and dense inputs look alike.
  /// 3 is close to the smoke demo scene (smoke1 with σt 0.8 has τ̄ ≈ 3.6): dense enough that
  /// the core saturates and the thin smoke around it shows, where fits go wrong.
  double meanOpticalDepth = 3.0;
  /// The density volume's voxels are the input's cells, scaled down to at most this many.
  std::int64_t maxVoxels = 256 * 256 * 256;
};

/// A scene that shows `input` as a user would see it, for judging a fit in image space: the
/// medium box = the input's box, medium resolution = its dims (capped by view.maxVoxels),
/// σt by view.meanOpticalDepth, albedo 0.9, isotropic phase; a camera on the −z side looking
/// at the box centre (fov 40°, the box filling ~90 % of the frame); one directional light
/// travelling along normalize(−1, −1, 1) (from the upper right front); black background;
/// method `exact`. The density is `input` itself (DenseGridDensity); replace
/// scene.medium.density by the fitted model for the second image.
Scene sogCheckScene(const DensityGrid& input, const SogCheckView& view = {});

/// Relative L2 of `approx` against `ref` over their cells (same dims).
double relativeL2(const std::vector<float>& approx, const std::vector<float>& ref);

/// Box-filters `g` by an integer factor in each axis (cells averaged; the box is kept, so the
/// last coarse cell may average fewer fine cells).
DensityGrid downsample(const DensityGrid& g, int factor);

}  // namespace scatterlab
