#include "core/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "core/error.h"

namespace scatterlab {

namespace {

void checkSizes(const Image& img, const Image& ref) {
  if (img.width() != ref.width() || img.height() != ref.height())
    throw ConfigError("image sizes differ: " + std::to_string(img.width()) + "x" +
                      std::to_string(img.height()) + " vs reference " +
                      std::to_string(ref.width()) + "x" + std::to_string(ref.height()));
  if (img.pixels().empty())
    throw ConfigError("the images are empty (" + std::to_string(img.width()) + "x" +
                      std::to_string(img.height()) + " pixels): there is nothing to compare");
  // A NaN difference compares false everywhere (max, > threshold) and an inf reference made
  // rel. L2 -nan: both used to pass as a perfect match.
  for (const auto& [what, im] : {std::pair<const char*, const Image*>{"image", &img},
                                 std::pair<const char*, const Image*>{"reference", &ref}})
    if (const NonFiniteValues bad = countNonFinite(*im, /*withAlpha=*/false); bad.any())
      throw ConfigError(std::string("the ") + what + " has " + bad.describe() +
                        "; the error measures need finite pixels");
}

/// num/den as a ratio, with 0/0 = 0 (equal black images) and x/0 = inf.
double ratio(double num, double den) {
  return den > 0 ? num / den : (num > 0 ? std::numeric_limits<double>::infinity() : 0.0);
}

/// The single pass behind both compareImages(): `mask` may be null.
ImageError measure(const Image& img, const Image& ref, const LightMask* mask) {
  checkSizes(img, ref);
  double d2 = 0, b2 = 0, d1 = 0, b1 = 0, mse = 0, maxAbs = 0, md2 = 0, mb2 = 0;
  std::size_t wrong = 0, kept = 0;
  const std::size_t n = img.pixels().size();
  for (std::size_t i = 0; i < n; ++i) {
    double pd2 = 0, pb2 = 0, pt = 0;
    for (int c = 0; c < 3; ++c) {
      const double a = img.pixels()[i][c], b = ref.pixels()[i][c];
      const double d = a - b;
      pd2 += d * d;
      pb2 += b * b;
      d1 += std::abs(d);
      b1 += std::abs(b);
      maxAbs = std::max(maxAbs, std::abs(d));
      // The PNG transform (writePng): exposure 0, clamp, sRGB curve; no 8-bit rounding.
      const double t = double(toneMapSrgb(float(a))) - double(toneMapSrgb(float(b)));
      mse += t * t;
      pt = std::max(pt, std::abs(t));
    }
    d2 += pd2;
    b2 += pb2;
    wrong += pt > kVisibleThreshold;
    if (mask && !mask->px[i]) {
      md2 += pd2;
      mb2 += pb2;
      ++kept;
    }
  }
  ImageError e;
  e.relL2 = std::sqrt(ratio(d2, b2));
  e.relL1 = ratio(d1, b1);
  mse /= double(n * 3);
  e.psnr = mse > 0 ? 10.0 * std::log10(1.0 / mse) : std::numeric_limits<double>::infinity();
  e.maxAbs = maxAbs;
  e.visiblyWrong = n ? double(wrong) / double(n) : 0.0;
  if (mask) {
    e.maskRadius = mask->radius;
    e.maskedLights = mask->lights;
    if (kept) e.maskedRelL2 = std::sqrt(ratio(md2, mb2));
  }
  return e;
}

}  // namespace

std::size_t LightMask::maskedPixels() const {
  return std::size_t(std::count(px.begin(), px.end(), 1));
}

double defaultMaskRadius(int width, int height) {
  return std::max(2.0, 0.01 * std::hypot(double(width), double(height)));
}

LightMask lightMask(const Scene& scene, double radius) {
  LightMask m;
  m.width = scene.camera.width;
  m.height = scene.camera.height;
  m.radius = radius;
  m.px.assign(std::size_t(m.width) * m.height, 0);
  for (const Light& l : scene.lights) {
    if (l.type == Light::Type::Directional) continue;
    float lx = 0, ly = 0;
    if (!scene.camera.project(l.position, lx, ly)) continue;                 // behind the camera
    if (!(lx >= 0 && lx <= m.width && ly >= 0 && ly <= m.height)) continue;  // off the image
    ++m.lights;
    const int x0 = std::max(0, int(std::floor(lx - radius))),
              x1 = std::min(m.width - 1, int(std::ceil(lx + radius)));
    const int y0 = std::max(0, int(std::floor(ly - radius))),
              y1 = std::min(m.height - 1, int(std::ceil(ly + radius)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double dx = x + 0.5 - lx, dy = y + 0.5 - ly;  // from the pixel centre
        if (dx * dx + dy * dy <= radius * radius) m.px[std::size_t(y) * m.width + x] = 1;
      }
  }
  return m;
}

ImageError compareImages(const Image& img, const Image& ref) {
  return measure(img, ref, nullptr);
}

ImageError compareImages(const Image& img, const Image& ref, const LightMask& mask) {
  checkSizes(img, ref);
  if (mask.width != img.width() || mask.height != img.height())
    throw ConfigError("the scene's camera is " + std::to_string(mask.width) + "x" +
                      std::to_string(mask.height) + " but the images are " +
                      std::to_string(img.width()) + "x" + std::to_string(img.height()) +
                      "; give the scene the overrides the images were rendered with (--set "
                      "camera.width=..., camera.height=...)");
  return measure(img, ref, &mask);
}

}  // namespace scatterlab
