#pragma once
/// Shared pieces of the GPU tests: skip without a context, small scenes, error measures.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "core/grid.h"
#include "core/image.h"
#include "gpu/context.h"
#include "support/scenes.h"

namespace scatterlab::testing {

/// Skips the test (with the reason) when no EGL/OpenGL 4.5 context can be made.
#define SCATTERLAB_REQUIRE_GPU()                                     \
  do {                                                               \
    std::string why_;                                                \
    if (!::scatterlab::gpu::tryContext(&why_)) GTEST_SKIP() << why_; \
  } while (0)

/// A small Gaussian-blob medium in [0,1]³ with a point light and a spot light, HG phase.
inline Json blobSceneDoc(int resolution, int width, int height) {
  return Json{
      {"medium",
       {{"bounds", {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}}},
        {"density",
         {{"type", "gaussians"},
          {"blobs",
           Json::array({{{"center", {0.5, 0.5, 0.5}}, {"radius", 0.15}, {"weight", 1.0}},
                        {{"center", {0.35, 0.6, 0.45}}, {"radius", 0.12}, {"weight", 0.8}},
                        {{"center", {0.68, 0.38, 0.55}}, {"radius", 0.14}, {"weight", 0.9}},
                        {{"center", {0.9, 0.9, 0.2}}, {"radius", 0.08}, {"weight", 0.5}}})}}},
        {"resolution", resolution},
        {"sigma_t", 4.0},
        {"albedo", 0.6},
        {"phase", {{"type", "henyey-greenstein"}, {"g", 0.3}}}}},
      {"lights",
       Json::array(
           {{{"type", "point"}, {"position", {0.55, 0.55, 0.45}}, {"intensity", {6, 4.5, 3}}},
            {{"type", "spot"},
             {"position", {0.5, 1.4, 0.5}},
             {"direction", {0, -1, 0}},
             {"intensity", {3, 3, 4}},
             {"inner_deg", 15},
             {"outer_deg", 30}}})},
      {"camera",
       {{"position", {0.5, 0.5, -2}},
        {"look_at", {0.5, 0.5, 0.5}},
        {"fov_y_deg", 35},
        {"width", width},
        {"height", height}}},
      {"render", {{"method", "per-voxel"}}}};
}

/// One render of `doc` on `backend` ("cpu" or "gpu"), the method and settings the document gives.
inline RenderResult renderOn(const Json& doc, const char* backend) {
  const Scene s = sceneFromJson(doc);
  return createMethod(s, "", backend)->render(s, nullptr);
}

}  // namespace scatterlab::testing
