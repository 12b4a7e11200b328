#pragma once
/// Signed error maps and their colour scale: the gallery's second row (experiment/gallery.cpp)
/// and `scatterlab compare --diff-signed` draw the same pictures.

#include "core/image.h"

namespace scatterlab {

/// Display-space difference shown at full colour in the signed error maps: a mean channel
/// difference of ±0.1 after the PNG transform (toneMapSrgb, exposure 0), twice the
/// visibly-wrong threshold kVisibleThreshold.
inline constexpr double kErrorMapFull = 0.1;

/// Signed error map of `img` against `ref` (same size) in display units (the visibly-wrong
/// metric's): per pixel Δ = mean over channels of toneMapSrgb(a) − toneMapSrgb(b); red where the
/// image is brighter, blue where darker, black where equal, full at |Δ| = kErrorMapFull. Returned
/// as linear values that show as those colours in a PNG written with `exposure` stops (and the
/// linear tone curve): the colour's sRGB value is min(1, |Δ| / kErrorMapFull).
Image signedErrorMap(const Image& img, const Image& ref, float exposure = 0.0f);

/// The colour scale of the signed error maps in an image `w`×`h`: a bar from blue
/// (−kErrorMapFull, left) through black (0) to red (+kErrorMapFull, right) in a white frame,
/// its ends and middle labelled below and "ERROR SCALE" above where they fit. Linear values, as
/// signedErrorMap's.
Image errorScale(int w, int h, float exposure = 0.0f);

/// `compare --diff-signed`'s picture: signedErrorMap(img, ref) with errorScale below it after a
/// 4-pixel black gap, W×(H + 4 + 30·s) pixels for a W×H image, s = 1 up to W = 259, 2 up to
/// 389, else 3 (the font scale of the bar's labels, which fit from W = 55·s).
Image signedErrorMapWithScale(const Image& img, const Image& ref, float exposure = 0.0f);

}  // namespace scatterlab
