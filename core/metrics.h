#pragma once
/// Image error metrics, the one implementation behind `scatterlab compare` and the experiment
/// harness (definitions and rationale: docs/metrics.md). ImageError and the unmasked
/// compareImages() are declared in core/image.h; this header adds the light mask.

#include <vector>

#include "core/image.h"
#include "core/scene.h"

namespace scatterlab {

/// Pixels excluded from the masked relative L2: discs of `radius` pixels around the projections
/// of the point and spot lights onto the image.
struct LightMask {
  int width = 0, height = 0;
  double radius = 0.0;            ///< in pixels, as reported with the number
  int lights = 0;                 ///< lights whose projection lies on the image (masked)
  std::vector<unsigned char> px;  ///< width·height, row-major; 1 = excluded
  std::size_t maskedPixels() const;
};

/// The default mask radius: 1 % of the image diagonal, at least 2 px. A 1/d² glow concentrates
/// its squared error in a few pixels next to the light; this covers them at any image size.
double defaultMaskRadius(int width, int height);

/// The mask for an image of the scene's camera size. A pixel is excluded when its centre lies
/// within `radius` pixels of a point or spot light's projection (Camera::project); lights behind
/// the camera, outside the image rectangle, and directional lights mask nothing.
LightMask lightMask(const Scene& scene, double radius);

/// compareImages() plus the masked relative L2 over the pixels `mask` keeps (NaN when it keeps
/// none). Throws ConfigError when the mask's size differs from the images'.
ImageError compareImages(const Image& img, const Image& ref, const LightMask& mask);

}  // namespace scatterlab
