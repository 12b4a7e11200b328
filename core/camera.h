#pragma once
/// Pinhole camera. Pixel (0, 0) is the top-left pixel; rays pass through pixel centres.

#include "core/math.h"

namespace scatterlab {

struct Camera {
  Vec3 position{0.5f, 0.5f, -2.0f};
  Vec3 lookAt{0.5f};
  Vec3 up{0.0f, 1.0f, 0.0f};
  float fovYDeg = 40.0f;  ///< vertical field of view in degrees, in (0, 180)
  /// The largest camera.width and camera.height a scene may give (and `render -r`).
  static constexpr int kMaxSide = 16384;
  int width = 320;
  int height = 240;
  /// Samples per pixel: a k x k grid of stratum centres (k² = spp), averaged (box filter).
  int spp = 1;

  /// Orthonormal frame: forward (towards look_at), right, true up. Throws ConfigError when
  /// position == look_at or up is parallel to the view direction.
  void frame(Vec3& forward, Vec3& right, Vec3& trueUp) const;

  /// World-space primary ray through the centre of pixel (px, py), row 0 at the top.
  /// Convenience for single rays; loops use rayGenerator(), which builds the frame once.
  Ray primaryRay(int px, int py) const;

  /// Precomputed frame for generating many primary rays.
  struct RayGenerator {
    Vec3 origin, forward, right, up;
    float sx, sy;  ///< tan(fov/2) * aspect, tan(fov/2)
    int width, height;
    Ray operator()(int px, int py) const { return at(px + 0.5f, py + 0.5f); }
    /// The ray through continuous image coordinates (fx, fy): x right, y down, pixel (i, j)
    /// covering [i, i+1) x [j, j+1).
    Ray at(float fx, float fy) const {
      const float u = (fx / width * 2.0f - 1.0f) * sx;
      const float v = (1.0f - fy / height * 2.0f) * sy;
      return Ray{origin, glm::normalize(forward + u * right + v * up)};
    }
  };
  RayGenerator rayGenerator() const;

  /// View depths (distances along the forward axis from the eye) of a box's nearest and
  /// farthest corners; `near` is negative when a corner lies behind the eye.
  struct DepthRange {
    float near, far;
  };
  /// The view-depth range of `box` seen from `gen`: what froxel slices and the paper's
  /// view-plane slabs span.
  static DepthRange viewDepthRange(const RayGenerator& gen, const Box& box);

  /// Projects a world point to continuous pixel coordinates (x right, y down); returns false
  /// when the point is behind the camera.
  bool project(const Vec3& p, float& px, float& py) const;
};

}  // namespace scatterlab
