#include "cpu/shadow_map.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <glm/glm.hpp>

namespace scatterlab {

ShadowMap::ShadowMap(const Scene& scene, const ShadowMapSettings& settings)
    : s_(settings), proj_(shadowProjections(scene, settings.resolution)) {
  const int res = s_.resolution;
  const SceneObjects& objects = *scene.objects;
  depth_.assign(proj_.layers.size() * std::size_t(res) * res, 0.0f);
  const int rows = int(proj_.layers.size()) * res;
  tbb::parallel_for(tbb::blocked_range<int>(0, rows), [&](const tbb::blocked_range<int>& rr) {
    for (int row = rr.begin(); row < rr.end(); ++row) {
      const ShadowLayer& l = proj_.layers[std::size_t(row / res)];
      const glm::dmat4 inv = glm::inverse(glm::dmat4(l.viewProj));
      const int j = row % res;
      for (int i = 0; i < res; ++i) {
        // The texel centre's ray: from the light (perspective) or from the eye plane (ortho),
        // through the far plane's point of the centre.
        const double x = (i + 0.5) / res * 2.0 - 1.0, y = (j + 0.5) / res * 2.0 - 1.0;
        const glm::dvec4 nearP = inv * glm::dvec4(x, y, -1.0, 1.0);
        const glm::dvec4 farP = inv * glm::dvec4(x, y, 1.0, 1.0);
        const Vec3 a = Vec3(glm::dvec3(nearP) / nearP.w), b = Vec3(glm::dvec3(farP) / farP.w);
        const Ray ray = l.ortho ? Ray{a, l.direction} : Ray{l.origin, glm::normalize(b - l.origin)};
        SurfaceHit hit;
        float& d = depth_[std::size_t(row) * res + i];
        d = l.far;
        // d is the distance from the light, or the depth from the eye plane (the ray's start).
        if (objects.intersect(ray, 0.0f, l.far, hit)) d = hit.t;
      }
    }
  });
}

float ShadowMap::visibility(int light, const Vec3& x) const {
  int layer;
  glm::vec2 uv;
  float d, texel;
  if (!shadowLookup(proj_, light, x, layer, uv, d, texel)) return 1.0f;
  const int res = s_.resolution;
  const float z = d - s_.bias * texel;
  const int ci = int(std::min(uv.x * float(res), float(res) - 1.0f));
  const int cj = int(std::min(uv.y * float(res), float(res) - 1.0f));
  const int r = s_.filter / 2;
  float lit = 0.0f;
  for (int j = -r; j <= r; ++j)
    for (int i = -r; i <= r; ++i) {
      const int ti = std::clamp(ci + i, 0, res - 1), tj = std::clamp(cj + j, 0, res - 1);
      lit += z <= depth_[(std::size_t(layer) * res + tj) * res + ti] ? 1.0f : 0.0f;
    }
  return lit / float((2 * r + 1) * (2 * r + 1));
}

}  // namespace scatterlab
