#pragma once
/// CPU shadow maps of the scene objects (Tóth & Umenhoffer 2009, Sec. 4), the CPU twin of
/// gpu/shadow_maps.h: per light the maps of shading/shadow_projection.h (2D perspective for a
/// spot, a cube for a point light or a spot wider than 120°, orthographic for a directional
/// light), render.shadow_map.resolution texels a side, each texel holding the distance metric
/// d of the nearest surface along one Embree ray through the texel's centre (where the GPU
/// rasterises the same texel centres). visibility() is the depth compare of shadow.glsl's
/// `depth` type: V = [d(x) − bias·texel ≤ d_map], averaged over filter × filter texels (PCF).
/// Variance shadow maps (type `vsm`, the GPU default) are GPU only: the CPU compares depths
/// whatever the type (docs/light-space-march.md). Used by light-space-march for the
/// visibility v_l(x) of its sample points.

#include <vector>

#include "core/stages.h"
#include "shading/shadow_projection.h"

namespace scatterlab {

class ShadowMap {
 public:
  /// The maps of every light of `scene` (which must have objects), with `settings`'
  /// resolution, bias and filter.
  ShadowMap(const Scene& scene, const ShadowMapSettings& settings);

  /// V of light `light` at x: 1 lit, 0 shadowed, in between on a PCF penumbra; 1 where x falls
  /// outside the light's maps.
  float visibility(int light, const Vec3& x) const;

  int layers() const { return int(proj_.layers.size()); }

 private:
  ShadowMapSettings s_;
  ShadowProjections proj_;
  std::vector<float> depth_;  ///< layers × res × res, row j at map v = (j + ½)/res
};

}  // namespace scatterlab
