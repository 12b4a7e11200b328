#pragma once
/// Scenes built in code for tests and benchmarks.

#include <cmath>

#include "api/scatterlab.h"
#include "methods/register.h"

namespace scatterlab::testing {

/// Parses a scene document given as a JSON literal (relative paths resolve from the source
/// tree's data/ folder). Calls initialize().
inline Scene sceneFromJson(const Json& doc) {
  initialize();
  return parseScene(doc, SCATTERLAB_SOURCE_DIR "/data");
}

/// Relative L2 of a against the reference b (core's definition, docs/metrics.md).
inline double relL2(const Image& a, const Image& b) {
  return compareImages(a, b).relL2;
}

/// The shipped VDB files' folder and the glow scene (data/).
inline const std::string kVdb = SCATTERLAB_SOURCE_DIR "/data/vdb/";
inline const std::string kGlow = SCATTERLAB_SOURCE_DIR "/data/scenes/glow.json";

/// A render object that keeps the sampled path of a method with a whole-scene fallback
/// (MethodDesc::wholeSceneFallback: gradient, adaptive), not the fallback that renders a small
/// test volume as per-voxel does (key voxel_switch 0), for tests of the samples themselves; other
/// methods' objects unchanged.
inline Json sampledPath(Json render) {
  const std::string m = render.value("method", "");
  for (const MethodDesc& d : builtinMethods())
    if (d.name == m && !d.wholeSceneFallback.empty()) render["voxel_switch"] = 0;
  return render;
}

/// Appends `n` point lights of intensity `I` (RGB) to doc["lights"], on a horizontal ring of
/// radius `radius` about (0.5, y, 0.5): many lamps inside the unit box.
inline void addRingOfLamps(Json& doc, int n, double radius, double y, const Json& I) {
  for (int i = 0; i < n; ++i) {
    const double phi = 2.0 * 3.14159265358979 * i / n;
    doc["lights"].push_back(
        {{"type", "point"},
         {"position", {0.5 + radius * std::cos(phi), y, 0.5 + radius * std::sin(phi)}},
         {"intensity", I}});
  }
}

/// Homogeneous unit box [0,1]³ of density `density`, one isotropic point light of intensity
/// `I` at `light`, camera at (0.5, 0.5, -2) looking at the box centre.
inline Json homogeneousBoxDoc(float density, float sigmaT, float albedo, Vec3 light, float I,
                              int width, int height, int resolution) {
  return Json{{"medium",
               {{"bounds", {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}}},
                {"density", {{"type", "uniform"}, {"value", density}}},
                {"resolution", resolution},
                {"sigma_t", sigmaT},
                {"albedo", albedo}}},
              {"lights", Json::array({{{"type", "point"},
                                       {"position", {light.x, light.y, light.z}},
                                       {"intensity", {I, I, I}}}})},
              {"camera",
               {{"position", {0.5, 0.5, -2}},
                {"look_at", {0.5, 0.5, 0.5}},
                {"fov_y_deg", 30},
                {"width", width},
                {"height", height}}}};
}

}  // namespace scatterlab::testing
