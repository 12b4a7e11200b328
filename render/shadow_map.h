#pragma once
/// CPU shadow maps of the scene objects (Tóth & Umenhoffer 2009, Sec. 4): a depth map per light,
/// built by casting one Embree ray through the centre of every texel — a 2D perspective map for
/// a spot light whose outer half-angle is at most 80°, a cube map (six 90° faces) for point
/// lights and wider spots, an orthographic map over the medium box for directional lights.
/// visibility(x) is the shadow-map test: 1 when nothing is nearer the light in x's texel (with a
/// bias of two texels' width at x's distance), else 0. Used by light-space-march for the
/// visibility v(x) of its sample points (docs/light-space-march.md).

#include <vector>

#include "core/light.h"
#include "core/objects.h"

namespace scatterlab {

class ShadowMap {
 public:
  /// The map of `light` over `objects`, `resolution` texels per side (per face), covering the
  /// medium box `medium` (what the directional map spans).
  ShadowMap(const Light& light, const SceneObjects& objects, const Box& medium, int resolution);

  /// 1 when x is lit by the light as far as the map sees, 0 when an object is nearer the light.
  float visibility(const Vec3& x) const;

  int faces() const { return int(faces_.size()); }

 private:
  /// One perspective face (origin at the light) or the orthographic map.
  struct Face {
    Vec3 forward, right, up;
    float tanHalf = 1.0f;  ///< perspective: tan of the half field of view
  };
  /// The texel of x on face f and x's depth there (distance from the light, or along the
  /// directional light's direction); false when x is outside the face.
  bool lookup(int f, const Vec3& x, int& i, int& j, float& depth, float& texel) const;

  bool ortho_ = false;
  Vec3 origin_{0.0f};  ///< the light's position (perspective faces)
  float uMin_ = 0, vMin_ = 0, cellU_ = 1, cellV_ = 1, start_ = 0;  ///< orthographic map
  int res_ = 1;
  std::vector<Face> faces_;
  std::vector<float> depth_;  ///< faces × res × res, infinity where no object is hit
};

}  // namespace scatterlab
