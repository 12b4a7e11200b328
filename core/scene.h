#pragma once
/// The scene: medium, lights, camera, background and the render settings, loaded from JSON
/// (documented key by key in docs/scene-format.md).

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/density_model.h"
#include "core/light.h"
#include "core/objects.h"
#include "core/params.h"
#include "core/phase.h"

namespace scatterlab {

struct Medium {
  Box bounds;                                   ///< world-space box B; D = 0 outside
  std::shared_ptr<const DensityModel> density;  ///< D(x) >= 0
  IVec3 resolution{128};                        ///< density (and radiance) volume voxels
  float sigmaT = 1.0f;                          ///< extinction per unit density, >= 0
  float albedo = 1.0f;                          ///< Ω in [0, 1]; σs = Ω·σt
  Phase phase;

  float sigmaS() const { return albedo * sigmaT; }
  /// Smallest voxel edge: the default step for marching and volume tracing.
  float voxelSize() const;
};

struct Scene {
  Medium medium;
  std::vector<Light> lights;
  Camera camera;
  Vec3 background{0.0f};
  /// Occluders and surfaces (the `objects` array); null when the scene has none.
  std::shared_ptr<const SceneObjects> objects;
  Json render = Json::object();   ///< the "render" object, parsed by the chosen method
  std::filesystem::path baseDir;  ///< directory of the scene file
};

/// Parses a scene document. Throws ConfigError naming the key, the value and what is allowed;
/// IoError for files the scene refers to. With `keepMedium`, the document's medium is not read
/// (nor its files loaded) and the scene takes *keepMedium instead: re-parsing lights, camera
/// and render settings over a medium already built (api/renderer.h).
Scene parseScene(const Json& doc, const std::filesystem::path& baseDir,
                 const Medium* keepMedium = nullptr);

/// Reads the JSON file at `path` (IoError when missing, a directory or malformed), applies the
/// `--set` overrides in order, and parses it.
Scene loadScene(const std::string& path, const std::vector<std::string>& overrides = {});

/// Reads and parses a JSON file without interpreting it. Throws IoError with line/column.
Json readJsonFile(const std::string& path);

/// A light as the scene format writes it (docs/scene-format.md): parseScene of it gives the
/// light back (spot cones in degrees from their cosines, rounded to 1e-4°).
Json lightJson(const Light& light);
/// The camera as the scene format writes it.
Json cameraJson(const Camera& camera);

}  // namespace scatterlab
