#pragma once
/// Pictures of a sample set: the samples projected through the camera over a dimmed copy of
/// the rendered image, coloured by dynamic-sampling level (the insets of the paper's Fig. 4/5).

#include <cstddef>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/stages.h"

namespace scatterlab {

/// Colour of level l: 0 white, 1 green, 2 yellow, 3 red, 4+ magenta.
Vec3 levelColour(int level);

/// Largest share of the area a level's samples project to (the 4×4-pixel blocks they fall in)
/// that its dots may cover.
inline constexpr double kSampleCover = 0.5;

/// How one level's dots are drawn: a disc of `radius` pixels (2, 1 or 0 = one pixel), blended
/// over the image with `opacity`.
struct DotStyle {
  int radius = 2;
  float opacity = 1.0f;
};

/// The dots for `count` samples projecting to `span` pixels: the largest radius whose discs
/// cover at most kSampleCover·span pixels in all, else one pixel each at the opacity that
/// covers that much (overlapping dots then add up: brighter where more samples lie along the
/// view).
DotStyle dotStyle(std::size_t count, std::size_t span);

/// `base` dimmed by `dim` with every sample drawn as a dot in its level's colour (value
/// `bright`, linear radiance), finer levels on top; each level's dots sized by dotStyle(), so
/// that dense sets (thousands of samples through a volume, no splits) stay dots instead of a
/// solid block.
Image drawSamples(const Image& base, const std::vector<RadianceSample>& samples,
                  const Camera& camera, float dim = 0.3f, float bright = 1.0f);

}  // namespace scatterlab
