#include "shading/shadow_projection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

#include "core/error.h"

namespace scatterlab {

namespace {

/// Spots wider than this get a cube (one perspective map cannot hold them well).
constexpr float kMaxSpotFovDeg = 120.0f;

std::array<Vec3, 8> corners(const Box& b) {
  std::array<Vec3, 8> c;
  for (int i = 0; i < 8; ++i)
    c[i] = Vec3(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z);
  return c;
}

/// An up vector not parallel to `dir`.
Vec3 upFor(const Vec3& dir) {
  return std::abs(dir.y) < 0.9f ? Vec3(0, 1, 0) : Vec3(1, 0, 0);
}

/// Near and far distances of a perspective map from `pos` covering `b`.
void nearFar(const Vec3& pos, const Box& b, float& nearD, float& farD) {
  farD = 0.0f;
  for (const Vec3& c : corners(b)) farD = std::max(farD, glm::length(c - pos));
  farD = farD * 1.01f + 1e-6f;
  nearD = std::max(farD * 1e-5f, 1e-7f);
}

void addCube(const Vec3& pos, const Box& b, int res, ShadowLightMaps& rec,
             std::vector<ShadowLayer>& layers) {
  float n, f;
  nearFar(pos, b, n, f);
  rec.kind = 0;
  rec.origin = pos;
  rec.texel = 2.0f / float(res);  // 2·tan(45°)/res per unit distance
  const glm::mat4 proj = glm::perspective(glm::radians(90.0f), 1.0f, n, f);
  const Vec3 dirs[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const Vec3& d : dirs) {
    ShadowLayer l;
    l.viewProj =
        proj * glm::lookAt(pos, pos + d, std::abs(d.y) > 0.5f ? Vec3(0, 0, 1) : Vec3(0, 1, 0));
    l.origin = pos;
    l.far = f;
    layers.push_back(l);
  }
}

}  // namespace

ShadowProjections shadowProjections(const Scene& scene, int res) {
  if (!scene.objects) throw Error("shadowProjections: the scene has no objects");
  Box bounds = scene.medium.bounds;
  bounds.min = glm::min(bounds.min, scene.objects->bounds().min);
  bounds.max = glm::max(bounds.max, scene.objects->bounds().max);
  ShadowProjections out;
  for (const Light& light : scene.lights) {
    ShadowLightMaps rec;
    rec.firstLayer = int(out.layers.size());
    if (light.type == Light::Type::Point) {
      addCube(light.position, bounds, res, rec, out.layers);
    } else if (light.type == Light::Type::Spot) {
      const float half = std::acos(std::clamp(light.cosOuter, -1.0f, 1.0f));
      // A little wider than the cone, so that its edge is not at the map's edge.
      const float fov = std::min(2.0f * half * 1.05f + glm::radians(1.0f), glm::radians(179.0f));
      if (fov > glm::radians(kMaxSpotFovDeg)) {
        addCube(light.position, bounds, res, rec, out.layers);
      } else {
        float n, f;
        nearFar(light.position, bounds, n, f);
        rec.kind = 1;
        rec.origin = light.position;
        rec.texel = 2.0f * std::tan(0.5f * fov) / float(res);
        ShadowLayer l;
        const Vec3 d = glm::normalize(light.direction);
        l.viewProj = glm::perspective(fov, 1.0f, n, f) *
                     glm::lookAt(light.position, light.position + d, upFor(d));
        l.origin = light.position;
        l.far = f;
        out.layers.push_back(l);
      }
    } else {
      // Orthographic, fitted to the box in the light's view.
      const Vec3 d = glm::normalize(light.direction);
      const Vec3 centre = bounds.center();
      const float radius = 0.5f * glm::length(bounds.extent());
      const Vec3 eye = centre - d * (radius * 1.01f + 1e-6f);
      const glm::mat4 view = glm::lookAt(eye, centre, upFor(d));
      Vec3 lo(kInfinity), hi(-kInfinity);
      for (const Vec3& c : corners(bounds)) {
        const Vec3 v = Vec3(view * glm::vec4(c, 1.0f));
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
      }
      const float pad = 0.005f * std::max(hi.x - lo.x, hi.y - lo.y) + 1e-6f;
      lo -= Vec3(pad);
      hi += Vec3(pad);
      const float far = -lo.z * 1.01f + 1e-6f;  // view space looks down -z
      rec.kind = 2;
      rec.origin = eye;
      rec.direction = d;
      rec.texel = std::max(hi.x - lo.x, hi.y - lo.y) / float(res);
      ShadowLayer l;
      l.viewProj = glm::ortho(lo.x, hi.x, lo.y, hi.y, 0.0f, far) * view;
      l.origin = eye;
      l.direction = d;
      l.ortho = true;
      l.far = far;
      out.layers.push_back(l);
    }
    out.lights.push_back(rec);
  }
  return out;
}

bool shadowLookup(const ShadowProjections& p, int light, const Vec3& x, int& layer, glm::vec2& uv,
                  float& d, float& texel) {
  const ShadowLightMaps& s = p.lights[std::size_t(light)];
  layer = s.firstLayer;
  if (layer < 0) return false;
  if (s.kind == 2) {
    d = glm::dot(x - s.origin, s.direction);
    texel = s.texel;
  } else {
    const Vec3 v = x - s.origin;
    d = glm::length(v);
    texel = s.texel * d;
    if (s.kind == 0) {
      const Vec3 a = glm::abs(v);
      const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
      layer += 2 * axis + (v[axis] < 0.0f ? 1 : 0);
    }
  }
  const glm::vec4 c = p.layers[std::size_t(layer)].viewProj * glm::vec4(x, 1.0f);
  if (!(c.w > 0.0f)) return false;
  uv = glm::vec2(c) / c.w * 0.5f + 0.5f;
  return uv.x >= 0.0f && uv.y >= 0.0f && uv.x <= 1.0f && uv.y <= 1.0f;
}

}  // namespace scatterlab
