#pragma once
/// CPU samplers (DESIGN.md §3, stage "sampler"): where the source radiance is evaluated, and
/// how far each sample may be used (its valid radius R_j, paper Sec. 4).
///
///  - "gaussian-centres": x_j = c_j, R_j = radius_scale·r_j (default 3, the paper's culling
///    radius) for every Gaussian of a sum-of-Gaussians medium (DensityModel::gaussians()).
///    Optional `count`: keep only the `count` Gaussians of largest mass w·r³.
///  - "grid": one sample at the centre of every occupied cell of a regular grid over the medium
///    box; "jittered": one uniformly jittered sample per occupied cell (stratified sampling,
///    deterministic for a given `seed`). A cell is occupied when a density voxel centre inside
///    it has D > 0 (`skip_empty: false` keeps every cell). The cell size is chosen so that the
///    number of occupied cells is as close as possible to `count`; the actual number is what
///    the render stats report as `samples`.
///    Radius rule: R = radius_scale·h with h the largest cell edge. Defaults: grid 1.0 (the
///    paper's rule for grid samples, Sec. 5: "valid radius equal to the grid interval"; every
///    point of a cell is within its half-diagonal ≤ 0.87·h of the cell centre, so occupied
///    cells are covered), jittered 1.75 (≥ √3: the cell diagonal, so a sample anywhere in its
///    cell still covers the whole cell).

#include "core/stages.h"

namespace scatterlab {

/// Registers "gaussian-centres", "jittered" and "grid" in samplers(). Each factory reads its
/// keys from the render.sampler object ("type" is read by the caller) and rejects bad values
/// with a ConfigError naming the key.
void registerSamplers();

/// Key table of the render.sampler object (every sampler's keys; which sampler reads which is
/// in each row's meaning).
const std::vector<KeyDoc>& samplerKeys();

/// The memory of `count` radiance samples with their per-sample bookkeeping (bytes): what a
/// sampler's `count` is checked against, and what a render's memory plan counts for them.
double sampleSetBytes(double count);

/// Cell layout of the grid and jittered samplers, exposed for tests.
struct SampleCells {
  IVec3 dims{1};
  Vec3 cell{1.0f};            ///< cell edge lengths (world units)
  std::vector<int> occupied;  ///< linear indices (i + nx·(j + ny·k)) of the cells used, ascending
};

/// Chooses the cells for about `count` samples over a density volume's box of extent `ext` and
/// `nd` voxels (see file comment), the occupancy counted by `frame` (Frame::occupiedCells: a
/// GPU frame counts on the device, one small read per grid tried); with `atMost` the finest
/// grid with at most `count` occupied cells (1 cell if none has so few).
SampleCells chooseSampleCells(Frame& frame, const Vec3& ext, IVec3 nd, long long count,
                              bool skipEmpty, bool atMost = false);
/// The same over a host density volume (tests).
SampleCells chooseSampleCells(const DensityGrid& density, long long count, bool skipEmpty,
                              bool atMost = false);

}  // namespace scatterlab
