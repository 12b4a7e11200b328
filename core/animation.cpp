#include "core/animation.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace scatterlab {

std::vector<PathKey> readLightPath(const Json& light, const std::string& keyPath) {
  std::vector<PathKey> path;
  if (!light.is_object() || !light.contains("path")) return path;
  const Json& keys = light["path"];
  const std::string where = keyPath + ".path";
  if (!keys.is_array() || keys.empty())
    throw ConfigError("'" + where + "': expected a non-empty array of {\"t\": T, \"position\": " +
                      "[x,y,z]}, got " + describeValue(keys));
  for (size_t k = 0; k < keys.size(); ++k) {
    Params p(keys[k], where + "[" + std::to_string(k) + "]");
    PathKey key;
    key.t = p.number("t");
    if (!std::isfinite(key.t)) p.fail("t", "must be finite");
    key.position = p.vec3("position");
    p.finish();
    if (!path.empty() && !(key.t > path.back().t))
      p.fail("t", std::to_string(key.t) + " is not greater than the previous key's t = " +
                      std::to_string(path.back().t) + " (times must strictly increase)");
    path.push_back(key);
  }
  return path;
}

Vec3 pathPosition(const std::vector<PathKey>& path, double t) {
  if (t <= path.front().t) return path.front().position;
  if (t >= path.back().t) return path.back().position;
  const auto next = std::upper_bound(path.begin(), path.end(), t,
                                     [](double v, const PathKey& k) { return v < k.t; });
  const PathKey& b = *next;
  const PathKey& a = *(next - 1);
  const float u = float((t - a.t) / (b.t - a.t));
  return a.position + u * (b.position - a.position);
}

namespace {

bool nonZero(const Json& j) {
  if (j.is_number()) return j.get<double>() != 0.0;
  if (j.is_array())
    return std::any_of(j.begin(), j.end(), [](const Json& v) { return nonZero(v); });
  return true;  // malformed: let the parser say so
}

}  // namespace

bool densityMovesWithTime(const Json& d) {
  if (!d.is_object() || !d.contains("type") || !d["type"].is_string()) return true;
  const std::string type = d["type"].get<std::string>();
  if (type == "grid" || type == "vdb") return false;
  if (type == "sog") return d.contains("frames");
  if (type == "uniform" || type == "height") return d.contains("rate") && nonZero(d["rate"]);
  if (type == "gaussians") {
    if (!d.contains("blobs") || !d["blobs"].is_array()) return true;
    for (const Json& b : d["blobs"])
      if (b.is_object() && b.contains("velocity") && nonZero(b["velocity"])) return true;
    return false;
  }
  return true;  // dusty-room (wind), and types registered elsewhere
}

bool documentMovesWithTime(const Json& doc) {
  if (!doc.is_object()) return false;
  if (doc.contains("lights") && doc["lights"].is_array())
    for (const Json& l : doc["lights"])
      if (l.is_object() && l.contains("path")) return true;
  if (doc.contains("medium") && doc["medium"].is_object()) {
    const Json& medium = doc["medium"];
    return medium.contains("density") && densityMovesWithTime(medium["density"]) &&
           medium["density"].is_object();
  }
  return false;
}

Json sceneAtTime(const Json& doc, double t) {
  Json work = doc;
  if (work.is_object() && work.contains("lights") && work["lights"].is_array()) {
    Json& lights = work["lights"];
    for (size_t i = 0; i < lights.size(); ++i) {
      const std::vector<PathKey> path =
          readLightPath(lights[i], "lights[" + std::to_string(i) + "]");
      if (path.empty()) continue;
      const Vec3 p = pathPosition(path, t);
      lights[i]["position"] = {p.x, p.y, p.z};
      lights[i].erase("path");
    }
  }
  if (work.is_object() && work.contains("medium") && work["medium"].is_object()) {
    Json& medium = work["medium"];
    if (medium.contains("density") && densityMovesWithTime(medium["density"]) &&
        medium["density"].is_object())
      medium["density"]["time"] = t;
  }
  return work;
}

double documentTime(const Json& doc) {
  if (doc.is_object() && doc.contains("medium") && doc["medium"].is_object() &&
      doc["medium"].contains("density") && doc["medium"]["density"].is_object() &&
      doc["medium"]["density"].contains("time")) {
    // Checked here: sceneAtTime overwrites it for a density that moves, so a string or an
    // array used to become time 0 without a word.
    const Json& t = doc["medium"]["density"]["time"];
    if (!t.is_number())
      throw ConfigError("'medium.density.time': expected a number, got " + describeValue(t));
    return t.get<double>();
  }
  return 0.0;
}

}  // namespace scatterlab
