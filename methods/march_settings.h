#pragma once
/// The keys of the two per-pixel competitors of the paper's method (docs/competitors.md):
/// `jittered-march` (steps, jitter, downsample) and `froxel` (froxel_grid, depth_distribution,
/// near, far, light_transmittance, transmittance_map_resolution). Each is read here, in one
/// place, the same whichever backend runs; the tables are at the top of march_settings.cpp.

#include <vector>

#include "core/params.h"
#include "core/scene.h"
#include "core/stages.h"

namespace scatterlab {

/// Key table of `jittered-march` (render keys).
const std::vector<KeyDoc>& jitteredMarchKeys();
/// Key table of `froxel` (render keys).
const std::vector<KeyDoc>& froxelKeys();

/// Reads the keys of `jittered-march`; a ConfigError names the key that is wrong.
JitteredMarchSettings parseJitteredMarch(Params& render);
/// Reads the keys of `froxel`; a ConfigError names the key that is wrong.
FroxelSettings parseFroxel(Params& render);

}  // namespace scatterlab
