#pragma once

namespace scatterlab {

/// Adds the density models of media/ to densityModels(): uniform, gaussians, height, grid.
/// Called by scatterlab::initialize().
void registerMediaModels();

}  // namespace scatterlab
