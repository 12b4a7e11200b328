// Signed error maps and their colour scale (experiment/error_map.h): the gallery's second row
// and `scatterlab compare --diff-signed`.

#include "experiment/error_map.h"

#include <algorithm>
#include <cmath>

#include "experiment/detail.h"

namespace scatterlab {

namespace {

/// Inverse of the sRGB curve: the linear value that toneMapSrgb (exposure 0) shows as `v`.
float srgbToLinear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

Image signedErrorMap(const Image& img, const Image& ref, float exposure) {
  Image out(img.width(), img.height());
  const float unexpose = std::exp2(-exposure);
  for (std::size_t i = 0; i < out.pixels().size(); ++i) {
    float d = 0;
    for (int c = 0; c < 3; ++c)
      d += toneMapSrgb(img.pixels()[i][c]) - toneMapSrgb(ref.pixels()[i][c]);
    const float t = std::min(1.0f, std::abs(d / 3.0f) / float(kErrorMapFull));
    const float v = srgbToLinear(t) * unexpose;
    out.pixels()[i] = d > 0 ? Vec3(v, 0, 0) : Vec3(0, 0, v);
  }
  return out;
}

Image errorScale(int w, int h, float exposure) {
  Image out(w, h);
  const float unexpose = std::exp2(-exposure);
  const int scale = detail::labelScale(w), lineH = 9 * scale;
  const int y0 = h / 2 - std::max(2, h / 8), y1 = h / 2 + std::max(2, h / 8);
  for (int x = 0; x < w; ++x) {
    const float t = w > 1 ? 2.0f * float(x) / float(w - 1) - 1.0f : 0.0f;
    const float v = srgbToLinear(std::abs(t)) * unexpose;
    const Vec3 c = t > 0 ? Vec3(v, 0, 0) : Vec3(0, 0, v);
    for (int y = y0; y < y1; ++y) out.at(x, y) = c;
  }
  // A white frame around the bar, so that its black middle reads as part of it.
  const Vec3 white(unexpose, unexpose, unexpose);
  for (int x = 0; x < w; ++x)
    out.at(x, std::max(0, y0 - 1)) = out.at(x, std::min(h - 1, y1)) = white;
  const std::string lo = detail::fmt(-kErrorMapFull, "%g"), hi = detail::fmt(kErrorMapFull, "%+g");
  const int ty = y1 + 2 + scale;
  if (detail::textWidth(lo, scale) + detail::textWidth("0", scale) + detail::textWidth(hi, scale) +
              4 * scale <=
          w &&
      ty + 7 * scale <= h) {
    detail::drawText(out, 0, ty, lo, scale, white);
    detail::drawText(out, (w - detail::textWidth("0", scale)) / 2, ty, "0", scale, white);
    detail::drawText(out, w - detail::textWidth(hi, scale), ty, hi, scale, white);
  }
  for (const char* title : {"ERROR SCALE", "SCALE"})
    if (detail::textWidth(title, scale) <= w && y0 - 2 - lineH >= 0) {
      detail::drawText(out, (w - detail::textWidth(title, scale)) / 2, y0 - 2 - lineH + scale,
                       title, scale, white);
      break;
    }
  return out;
}

Image signedErrorMapWithScale(const Image& img, const Image& ref, float exposure) {
  const Image map = signedErrorMap(img, ref, exposure);
  const int w = img.width(), h = img.height(), barH = 30 * detail::labelScale(w);
  const Image bar = errorScale(w, barH, exposure);
  Image out(w, h + 4 + barH);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) out.at(x, y) = map.at(x, y);
  for (int y = 0; y < barH; ++y)
    for (int x = 0; x < w; ++x) out.at(x, h + 4 + y) = bar.at(x, y);
  return out;
}

}  // namespace scatterlab
