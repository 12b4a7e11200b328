#pragma once
/// Pictures of a sample set: the samples projected through the camera over a dimmed copy of
/// the rendered image, coloured by dynamic-sampling level (the insets of the paper's Fig. 4/5).

#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/stages.h"

namespace scatterlab {

/// Colour of level l: 0 white, 1 green, 2 yellow, 3 red, 4+ magenta.
Vec3 levelColour(int level);

/// `base` dimmed by `dim` with every sample drawn as a small dot (2 px radius for level 0,
/// 1 px for finer levels; finer levels drawn on top), in linear radiance with value `bright`.
Image drawSamples(const Image& base, const std::vector<RadianceSample>& samples,
                  const Camera& camera, float dim = 0.3f, float bright = 1.0f);

}  // namespace scatterlab
