#pragma once
/// The projections of the shadow maps of scene objects (render.shadow_map, docs/objects.md),
/// in one place for the GPU maps (gpu/shadow_maps.h, rasterised) and the CPU ones
/// (cpu/shadow_map.h, cast with Embree through the same texel centres), so that both see
/// the same texels. Per light:
///   spot        one perspective map along the spot axis, field of view 2·outer half-angle
///               ·1.05 + 1° (a cube like a point light's when that exceeds 120°); d = |x − s|
///   point       a cube: six 90° perspective faces (+x, −x, +y, −y, +z, −z); d = |x − s|
///   directional one orthographic map fitted to the medium box ∪ the objects' bounds, looking
///               along the light; d = depth along the light's direction from the map's eye
/// and the lookup of a point (shadowLookup), the twin of shadow.glsl's.

#include <vector>

#include "core/math.h"
#include "core/scene.h"

namespace scatterlab {

/// One map layer: world → clip, and how its metric d is measured.
struct ShadowLayer {
  glm::mat4 viewProj{1.0f};
  Vec3 origin{0.0f};     ///< the light (perspective) or the orthographic map's eye
  Vec3 direction{0.0f};  ///< orthographic: the light's travel direction (unit)
  bool ortho = false;
  float far = 1.0f;  ///< the value of d where no surface is (the far plane)
};

/// One light's maps.
struct ShadowLightMaps {
  int firstLayer = -1;  ///< the layer of its map (a cube's +x face); -1: none
  int kind = 0;         ///< 0 cube (point, wide spot), 1 perspective (spot), 2 orthographic
  Vec3 origin{0.0f};    ///< light position; orthographic: the eye of the map
  /// World size of one texel per unit distance (perspective, cube), or in world units (ortho).
  float texel = 0.0f;
  Vec3 direction{0.0f};  ///< orthographic: the light's travel direction (unit)
};

struct ShadowProjections {
  std::vector<ShadowLightMaps> lights;  ///< per scene light, in order
  std::vector<ShadowLayer> layers;
};

/// The maps of every light of `scene` (which must have objects) at `resolution` texels a side.
ShadowProjections shadowProjections(const Scene& scene, int resolution);

/// Where x falls in light `light`'s maps: its layer, map coordinates uv in [0, 1]² (texel
/// (i, j) covers [i, i+1)/resolution), metric d and texel size at x; false when x falls outside
/// every map (nothing there can shadow it). The twin of shadow.glsl's shadowLookup.
bool shadowLookup(const ShadowProjections& p, int light, const Vec3& x, int& layer, glm::vec2& uv,
                  float& d, float& texel);

}  // namespace scatterlab
