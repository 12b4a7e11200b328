#pragma once
/// Linear RGB float images, OpenEXR and PNG I/O, image error measures (docs/metrics.md).

#include <array>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/math.h"

namespace scatterlab {

/// Row-major RGB image, row 0 at the top, linear radiance.
class Image {
 public:
  Image() = default;
  Image(int width, int height) : width_(width), height_(height), pixels_(size_t(width) * height) {}

  int width() const { return width_; }
  int height() const { return height_; }
  Vec3& at(int x, int y) { return pixels_[size_t(y) * width_ + x]; }
  const Vec3& at(int x, int y) const { return pixels_[size_t(y) * width_ + x]; }
  std::vector<Vec3>& pixels() { return pixels_; }
  const std::vector<Vec3>& pixels() const { return pixels_; }
  /// Coverage for compositing, row-major like pixels(): A = 1 − transmittance of the view ray
  /// through the medium, so that image + (1 − A)·plate puts the fog over a plate. Empty when
  /// the integrator does not record it (the GPU slice marcher); written as the EXR's A channel.
  std::vector<float>& alpha() { return alpha_; }
  const std::vector<float>& alpha() const { return alpha_; }
  /// Depth for compositing, row-major like pixels(): the camera-space depth (distance along
  /// the view axis, world units) of the view ray's expected first interaction — the medium's
  /// steps weighted by their opacity T·(1 − e^(−σt·D·Δt)) and an opaque surface by the T that
  /// reaches it — i.e. Σ w·z / A with A = alpha(); +∞ where nothing interacts (A = 0). Empty
  /// when the integrator does not record it (the CPU ray marcher and `exact` do); written as
  /// the EXR's Z channel.
  std::vector<float>& depth() { return depth_; }
  const std::vector<float>& depth() const { return depth_; }

 private:
  int width_ = 0, height_ = 0;
  std::vector<Vec3> pixels_;
  std::vector<float> alpha_;
  std::vector<float> depth_;
};

/// The non-finite values among an image's colour (RGB) and alpha channels; depth, whose +inf
/// means "nothing along the ray", is not counted.
struct NonFiniteValues {
  std::size_t nan = 0, inf = 0;
  int x = -1, y = -1;  ///< the first such pixel in row-major order (-1 when none)
  bool any() const { return nan + inf > 0; }
  /// "18 non-finite channel values (0 NaN, 18 inf; the first at pixel (31, 20))".
  std::string describe() const;
};
NonFiniteValues countNonFinite(const Image& img, bool withAlpha = true);

/// Header attributes of an EXR (render's provenance and camera, for compositing).
struct ExrAttributes {
  std::vector<std::pair<std::string, std::string>> strings;
  /// 4×4 matrices stored as Imath::M44f in its row-vector convention (p' = p·M), i.e. the
  /// 16 floats of a glm::mat4 in glm's memory order; e.g. OpenEXR's standard "worldToCamera"
  /// and "worldToNDC" (as pbrt-v4 writes them).
  std::vector<std::pair<std::string, std::array<float, 16>>> matrices;
};

/// Writes a 32-bit float RGB OpenEXR file (A and Z channels where alpha() and depth() are
/// non-empty) atomically (temporary file, then rename); on any
/// failure no file is left at `path`. The header's standard `chromaticities` attribute says
/// the colour space: linear, Rec. 709 primaries, D65 white. Throws IoError.
void writeExr(const Image& img, const std::string& path, const ExrAttributes& attributes = {});

/// Reads the R, G, B channels (and A into alpha(), Z into depth(), when the file has them) of an
/// OpenEXR file (missing channels read as 0; a file with none of them is an error). Throws IoError
/// naming the file.
Image readExr(const std::string& path);

/// The string and 4×4 float matrix attributes of an OpenEXR file's first part, in file order
/// (what writeExr's `attributes` wrote: `scatterlab info` shows them); the other attributes are
/// skipped. Throws IoError naming the file.
ExrAttributes readExrAttributes(const std::string& path);

/// Display transform used for PNG output and PSNR: multiply by 2^exposure, clamp to [0, 1],
/// encode with the sRGB transfer curve.
float toneMapSrgb(float linear, float exposure = 0.0f);

/// Tone curve applied before the sRGB encoding of PNG previews (`render --tonemap`, README):
/// Linear clamps at 1 (the default; what PSNR and "visibly wrong" use);
/// Filmic is Hable's Uncharted 2 curve normalised to white 11.2; Aces is Narkowicz's fit of the
/// ACES reference rendering transform. Both roll highlights off instead of clipping them.
enum class ToneCurve { Linear, Filmic, Aces };

/// Parses "linear", "filmic" or "aces"; ConfigError naming `key` and the allowed names else.
ToneCurve parseToneCurve(const std::string& name, const std::string& key = "--tonemap");

/// The curve on one linear value (after exposure), in [0, 1]; NaN and negatives give 0.
float toneCurve(float v, ToneCurve curve);

/// Writes an 8-bit sRGB PNG atomically: 2^exposure, then `curve`, then the sRGB encoding
/// (toneMapSrgb when Linear). Throws IoError; ConfigError when `exposure` is not within
/// [-100, 100] stops (NaN included).
void writePng(const Image& img, const std::string& path, float exposure = 0.0f,
              ToneCurve curve = ToneCurve::Linear);

/// Error of `img` against `ref` over all pixels and channels (docs/metrics.md). Computed in
/// core/metrics.cpp, the one implementation used by `compare` and the experiment harness.
struct ImageError {
  double relL2 = 0.0;   ///< sqrt(Σ(a−b)²) / sqrt(Σb²): the headline "relative error"
  double relL1 = 0.0;   ///< Σ|a−b| / Σ|b|
  double psnr = 0.0;    ///< dB on the tone-mapped (exposure 0, sRGB) image; +inf when equal
  double maxAbs = 0.0;  ///< max |a−b| in linear units
  /// Share of pixels where some channel of the tone-mapped images (toneMapSrgb, exposure 0:
  /// the PNG transform) differs by more than kVisibleThreshold.
  double visiblyWrong = 0.0;
  /// Relative L2 without the pixels near the lights (core/metrics.h: LightMask); NaN when no
  /// mask was given or it keeps no pixel.
  double maskedRelL2 = std::numeric_limits<double>::quiet_NaN();
  double maskRadius = std::numeric_limits<double>::quiet_NaN();  ///< px; NaN without a mask
  int maskedLights = 0;                                          ///< lights whose disc was excluded
};

/// Display-space difference above which a pixel counts as visibly wrong (0.05 of full scale,
/// about 13 of 255 PNG levels).
inline constexpr double kVisibleThreshold = 0.05;

/// Every measure but the masked one. Throws ConfigError when the sizes differ, when the images
/// are empty (0 pixels), or when either holds a NaN or infinite colour value (no measure means
/// anything then: NaN used to compare as a perfect match).
ImageError compareImages(const Image& img, const Image& ref);

}  // namespace scatterlab
