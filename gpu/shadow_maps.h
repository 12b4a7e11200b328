#pragma once
/// Shadow maps of scene objects, one per light (docs/objects.md "GPU"): the GPU's V_l, where
/// the CPU traces shadow rays through Embree. Reusable by any GL pass that needs visibility
/// towards the scene's lights: bind() them, prepend "shadow.glsl" to the program's files
/// (before common.glsl) with the define SL_OBJECTS, and call
///     float lightVisibility(int light, vec3 worldPos)                (points in the medium)
///     float surfaceVisibility(int light, vec3 worldPos, vec3 normal) (points on surfaces)
/// in GLSL: 1 lit, 0 shadowed, in between in a filtered penumbra. `light` indexes the scene's
/// lights (the order of common.glsl's lights[]).
///
/// Per light, every map stores the distance metric d of the nearest surface per texel (the
/// projections of shading/shadow_projection.h, which the CPU maps of cpu/shadow_map.h share):
///   spot        one perspective map along the spot axis, field of view 2·outer half-angle
///               (a cube like a point light's when that exceeds 120°); d = |x − s|
///   point       a cube: six 90° perspective faces (+x, −x, +y, −y, +z, −z); d = |x − s|
///   directional one orthographic map fitted to the medium box ∪ the objects' bounds, looking
///               along the light; d = depth along the light's direction
/// All maps are layers of one RG32F 2D array texture (resolution² texels each) holding the
/// moments (d, d²). Lookups (ShadowMapSettings, render.shadow_map):
///   depth  V = [d(x) − bias ≤ d_map], averaged over filter² texels (PCF) when filter > 1
///   vsm    the moments are box-blurred over filter texels; Chebyshev's one-sided bound
///          p = σ²/(σ² + (d − μ)²) where d − bias > μ (σ² ≥ (texel/2)²), then light-bleeding
///          reduction p' = clamp((p − b)/(1 − b), 0, 1) (Lauritzen, GPU Gems 3 ch. 8): without
///          it, a point behind two occluders at different depths sees a lit halo ("bleeding").
/// bias is in texels: one texel's world size at the point (distance·2·tan(fov/2)/resolution,
/// or the orthographic extent/resolution) times `bias`; surface lookups also move the point
/// that far along the normal (normal offset), against acne.
/// Everything here needs a current context.

#include <vector>

#include "core/scene.h"
#include "core/stages.h"
#include "gpu/gl.h"
#include "gpu/objects.h"
#include "gpu/shaders.h"
#include "gpu/timer.h"

namespace scatterlab::gpu {

/// shadow.glsl `ShadowLight` (shadowLights[] at BINDING_SHADOW_LIGHTS). std430: info 0,
/// origin 16, direction 32; stride 48.
struct GpuShadowLight {
  int firstLayer = -1;  ///< layer of the map (a cube's +x face); -1: no map (always lit)
  int kind = 0;         ///< 0 cube (point, wide spot), 1 perspective (spot), 2 orthographic
  int pad0 = 0, pad1 = 0;
  Vec3 origin{0.0f};  ///< light position; orthographic: the eye of the map (d measured from it)
  /// World size of one texel per unit distance (perspective, cube), or in world units (ortho).
  float texel = 0.0f;
  Vec3 direction{0.0f};  ///< orthographic: the light's travel direction (unit)
  float pad2 = 0.0f;
};
static_assert(sizeof(GpuShadowLight) == 48);

class ShadowMaps {
 public:
  /// Renders the maps of every light of `scene` (which must have objects) from `geometry`,
  /// timed into `timer` as "shadow maps" when given.
  ShadowMaps(const Scene& scene, const ObjectGeometry& geometry, const ShadowMapSettings& settings,
             StageTimer* timer = nullptr);
  /// Binds the maps, the per-light records and the per-layer matrices, and sets the lookup
  /// uniforms of `program` (in use), which must include shadow.glsl with SL_OBJECTS.
  void bind(const Program& program) const;
  const ShadowMapSettings& settings() const { return settings_; }
  int layers() const { return layers_; }
  /// The moments (d, d²) of layer `layer` (after the VSM blur), row-major, for tests.
  std::vector<float> readLayer(int layer) const;

 private:
  ShadowMapSettings settings_;
  int layers_ = 0;
  Texture maps_;
  Buffer lights_, matrices_;
};

/// Adds what a tracing program needs for visibility through `shadows` (when not null): the
/// define SL_OBJECTS and "shadow.glsl" before the other files of every stage.
ProgramVariant& addShadowVariant(const ShadowMaps* shadows, ProgramVariant& variant);

}  // namespace scatterlab::gpu
