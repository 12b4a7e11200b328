#pragma once
/// Shared geometry of the real-time post-process methods of the other seed documents, whose CPU
/// variants live in cpu/ and GPU variants in gpu/ (gpu/post_process.*; both sit above shading/,
/// so what both need is here): `light-space-march` (Tóth & Umenhoffer 2009,
/// docs/light-space-march.md) and `radial-blur` (Mitchell, GPU Gems 3 ch. 13, docs/radial-blur.md).
/// Each one's settings struct, key table and parser are here too (post_process.cpp), declared
/// by lightSpaceMarchStage() and radialBlurStage().

#include <algorithm>
#include <string>

#include "core/error.h"
#include "core/grid.h"
#include "core/scene.h"
#include "core/stages.h"

namespace scatterlab {

/// How light-space-march attenuates the light on its way to a sample point.
enum class LightTransmittance {
  /// Tóth & Umenhoffer's homogeneous model: e^(−σt·D̄·d), D̄ the mean of the density volume,
  /// d the length inside the medium box of the segment from the point to the light.
  Mean,
  /// The real density traced with step delta1 (what `exact` does), to separate the two errors.
  Traced,
};

/// `light-space-march`'s keys (lightSpaceMarchStage()).
struct LightSpaceMarchSettings {
  int steps = 128;     ///< N: terms of each view ray's sum, from the visible surface to the eye
  int interleave = 4;  ///< M: M×M pixel blocks, each pixel evaluates every M²-th term
  LightTransmittance light = LightTransmittance::Mean;
};

/// `radial-blur`'s keys (radialBlurStage()).
struct RadialBlurSettings {
  int samples = 64;        ///< n: samples per pixel along the screen ray towards the light
  float density = 1.0f;    ///< fraction of the pixel→light segment the n samples span
  float weight = 1.0f;     ///< per-sample scale
  float decay = 1.0f;      ///< sample i is scaled by decay^i
  float exposure = 1.0f;   ///< overall scale
  int downsample = 1;      ///< the pre-pass is rendered at 1/downsample of the image size
  float guardBand = 0.5f;  ///< the light's screen position is clamped to this margin (image sizes)
};

/// `light-space-march` (an integrator): its keys steps, interleave, light_transmittance into
/// PipelineSettings::integratorKeys (LightSpaceMarchSettings); own steps, no view march.
const StageDecl& lightSpaceMarchStage();
/// `radial-blur` (an integrator): its keys samples, density, weight, decay, exposure,
/// downsample, guard_band (RadialBlurSettings); the view march's keys for its pre-pass.
const StageDecl& radialBlurStage();

/// The stats of light-space-march, the same on every backend: steps, interleave,
/// terms_per_pixel, light_transmittance, mean_density (with the mean model: `meanDensity`),
/// shadow_maps (how many the objects needed).
void describeLightSpaceMarch(RenderStats& st, const LightSpaceMarchSettings& s, float meanDensity,
                             int shadowMaps);
/// The stats of radial-blur, the same on every backend: samples_per_pixel, downsample,
/// light_screen_positions (`positions`, one [x, y] per light).
void describeRadialBlur(RenderStats& st, const RadialBlurSettings& s, const Json& positions);

/// The mean of a density volume over all its voxels (D̄ of LightTransmittance::Mean).
inline float meanDensity(const DensityGrid& g) {
  double sum = 0.0;
  for (const float d : g.data()) sum += d;
  return g.data().empty() ? 0.0f : float(sum / double(g.data().size()));
}

/// The length inside `box` of the segment from x towards light `l` (to the light, or to the
/// box exit for directional lights): the d of e^(−σt·D̄·d).
inline float lengthInBox(const Light& l, const Light::Incident& inc, const Box& box,
                         const Vec3& x) {
  float t0, t1;
  const float tmax = l.type == Light::Type::Directional ? kInfinity : inc.distance;
  if (!box.intersect(Ray{x, inc.toLight}, t0, t1, 0.0f, tmax) || !(t1 > t0)) return 0.0f;
  return t1 - t0;
}

/// The pixel of the sliding M-wide window of the block sum that starts the window of pixel x
/// in an image `size` wide (size >= m): the window [start, start + m) holds x and one pixel of
/// every residue class mod m, and stays inside the image at its borders.
inline int blockWindowStart(int x, int m, int size) {
  return std::clamp(x - (m - 1) / 2, 0, size - m);
}

/// What light-space-march cannot render, as a ConfigError (CPU and GPU variants alike): an
/// interleave block larger than the image, or camera.spp > 1 (interleaved sampling shares the
/// terms of neighbouring pixels; several rays per pixel have no block structure).
inline void checkLightSpaceMarchScene(const Scene& scene, const LightSpaceMarchSettings& s) {
  const Camera& c = scene.camera;
  if (s.interleave > c.width || s.interleave > c.height)
    throw ConfigError("'render.interleave': " + std::to_string(s.interleave) +
                      " is larger than the image (" + std::to_string(c.width) + "x" +
                      std::to_string(c.height) + "); the M x M block must fit in it");
  if (c.spp > 1)
    throw ConfigError(
        "'camera.spp': light-space-march renders one ray per pixel (interleaved "
        "sampling sums neighbouring pixels' terms); set camera.spp to 1");
}

/// Light `index`'s position on the screen for the radial blur, in continuous pixel coordinates
/// (x right, y down, the image `camera.width` × `camera.height`), clamped to the guard band
/// [−g·W, (1+g)·W] × [−g·H, (1+g)·H] (Mitchell 13.6). A directional light's position is the
/// vanishing point of the direction towards it. Throws ConfigError when the light is behind
/// the camera (or in its plane): the blur has no point to blur towards.
inline void radialBlurLightPosition(const Scene& scene, int index, float guardBand, float& px,
                                    float& py) {
  const Light& l = scene.lights[std::size_t(index)];
  const Camera& cam = scene.camera;
  const Vec3 p = l.type == Light::Type::Directional
                     ? cam.position - l.direction * glm::length(scene.medium.bounds.extent())
                     : l.position;
  if (!cam.project(p, px, py))
    throw UnsupportedSceneError("radial-blur cannot render this scene: lights[" +
                                std::to_string(index) +
                                "] is behind the camera, and the screen-space blur needs the "
                                "light in front of it (Mitchell's method); use another method, "
                                "e.g. light-space-march or exact");
  const float w = float(cam.width), h = float(cam.height);
  px = std::clamp(px, -guardBand * w, (1.0f + guardBand) * w);
  py = std::clamp(py, -guardBand * h, (1.0f + guardBand) * h);
}

/// What radial-blur cannot render, as a ConfigError (CPU and GPU alike): camera.spp > 1 (one
/// ray per pixel); as an UnsupportedSceneError a light behind the camera
/// (radialBlurLightPosition) or a point or spot light inside the medium's box: the pre-pass's
/// unshadowed in-scattering peaks as 1/d² around it and the blur spreads that over the whole
/// frame (the glow scene: 7 586 % relative L1 against exact, 99.5 % of pixels visibly wrong).
/// Mitchell's method is for a light beyond the medium, the sun behind clouds. Returns nothing;
/// call it before any pass so that no partial image is made.
inline void checkRadialBlurScene(const Scene& scene, const RadialBlurSettings& s) {
  if (scene.camera.spp > 1)
    throw ConfigError("'camera.spp': radial-blur renders one ray per pixel; set camera.spp to 1");
  for (int l = 0; l < int(scene.lights.size()); ++l) {
    float x, y;
    radialBlurLightPosition(scene, l, s.guardBand, x, y);
    const Light& light = scene.lights[std::size_t(l)];
    const Box& box = scene.medium.bounds;
    if (light.type != Light::Type::Directional &&
        glm::all(glm::greaterThan(light.position, box.min)) &&
        glm::all(glm::lessThan(light.position, box.max)))
      throw UnsupportedSceneError(
          "radial-blur cannot render this scene: lights[" + std::to_string(l) +
          "] is inside the medium's box, and the screen-space blur stands for a light beyond "
          "the medium (Mitchell's method: the sun behind clouds); around a light inside it the "
          "blur spreads the light's glow over the whole frame. Use another method, e.g. "
          "light-space-march or exact");
  }
}

}  // namespace scatterlab
