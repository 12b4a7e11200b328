#pragma once
/// Animation of a scene document: light paths (`lights[i].path`) and the medium's `time`
/// (docs/scene-format.md, "Animation"). Used by loadScene (a document is read at its own time)
/// and by scatterlab::Renderer (api/renderer.h), which re-reads it at each frame's time.

#include <string>
#include <vector>

#include "core/math.h"
#include "core/params.h"

namespace scatterlab {

/// One key of a light path: position at time t.
struct PathKey {
  double t = 0.0;
  Vec3 position{0.0f};
};

/// Reads `lights[i].path` from a scene document (ConfigError naming lights[i].path[k] when it
/// is not a non-empty array of {t, position} with finite, strictly increasing t). Empty when
/// the light has no path.
std::vector<PathKey> readLightPath(const Json& light, const std::string& keyPath);

/// The position on `path` (non-empty) at time t: linear between keys, clamped at the ends.
Vec3 pathPosition(const std::vector<PathKey>& path, double t);

/// Whether the density object of a scene document changes with `time` (so a new time needs
/// a new density volume): procedural models with a non-zero rate, velocity or wind, noise
/// media, .sog frame sequences, and any type this function does not know.
bool densityMovesWithTime(const Json& density);

/// Whether sceneAtTime would change `doc` at some time: a light with a `path`, or a density
/// that moves with time. A document without either is its own scene at every time.
bool documentMovesWithTime(const Json& doc);

/// A scene document prepared at time t: light paths evaluated into `position` and removed,
/// and medium.density.time = t where the density moves with time. Throws ConfigError for a
/// malformed path.
Json sceneAtTime(const Json& doc, double t);

/// The time a document is at by itself: medium.density.time, else 0. A time that is not a
/// number is a ConfigError naming the key.
double documentTime(const Json& doc);

}  // namespace scatterlab
