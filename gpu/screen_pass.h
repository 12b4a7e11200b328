#pragma once
/// The set-up every per-pixel GPU pass shares (gpu/light_space_march.cpp, gpu/radial_blur.cpp:
/// light-space-march and radial-blur; gpu/screen_march.cpp: jittered-march and froxel): the scene
/// objects' shadow maps, the tracing inputs, the surface pass, programs with the shadow-map
/// variant, the camera uniforms, and the read-back of the RGBA32F result. Needs the GL context.

#include <string>
#include <vector>

#include "core/image.h"
#include "gpu/tracing.h"

namespace scatterlab::gpu {

/// One per-pixel pass's inputs, built in this order: the objects' shadow maps (when the scene
/// has objects; "shadow maps" in the timings), the tracing inputs over `density` with step
/// `delta1` and those maps, and the surface pass (ScreenSurfaces).
class ScreenPass {
 public:
  ScreenPass(const Scene& scene, const Volume& density, float delta1,
             const ShadowMapSettings& shadowMap, StageTimer* timer);
  ScreenPass(const ScreenPass&) = delete;
  ScreenPass& operator=(const ScreenPass&) = delete;

  /// The compute program of `files` with `defines` (with the shadow-map variant when the scene
  /// has objects), built once per variant; `label` names it.
  const Program& program(std::string_view label, std::vector<std::string> files,
                         std::vector<std::string> defines = {}) const;
  /// For `p` (in use): binds the tracing inputs and the surface textures and sets the camera
  /// uniforms (setScreenCamera).
  void bind(const Program& p) const;
  /// For a program that walks the density's empty-space grid (block_walk.glsl): builds it
  /// (TracingInputs::skipEmptySpace; before the program is made current), and bind() binds it.
  void skipEmptySpace(StageTimer* timer) { inputs_.skipEmptySpace(timer); }

  const ShadowMaps* shadows() const { return shadows_; }
  const TracingInputs& inputs() const { return inputs_; }

 private:
  const Scene& scene_;
  SceneShadows objects_;
  const ShadowMaps* shadows_;
  TracingInputs inputs_;
  ScreenSurfaces surfaces_;
};

/// The camera's ray frame as the per-pixel shaders read it (Camera::RayGenerator): uForward,
/// uRight, uUp, uTanHalf, the image size (ivec2 uImageSize or vec2 uSize, whichever the program
/// declares) and uAlbedo. `p` must be in use.
void setScreenCamera(const Program& p, const Scene& scene);

/// Binds a 2D RGBA32F image of the per-pixel passes to image unit `unit` (level 0, not layered).
void bindScreenImage(GLuint unit, const Texture& t, GLenum access);

/// What the alpha of a pass's RGBA32F output holds.
enum class OutputAlpha {
  Alpha,          ///< the image's alpha itself
  Transmittance,  ///< T: the image's alpha is 1 − T
};

/// Reads a w×h RGBA32F image back into an Image (rgb, and the alpha as `alpha` says). GPU
/// time: "read-back". Also the raster slice marcher's read-back (SliceMarcher).
Image readScreenImage(const Texture& t, int w, int h, OutputAlpha alpha, const char* pass,
                      StageTimer* timer);

}  // namespace scatterlab::gpu
