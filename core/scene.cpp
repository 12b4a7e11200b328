#include "core/scene.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/animation.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace scatterlab {

float Medium::voxelSize() const {
  const Vec3 c = bounds.extent() / Vec3(resolution);
  return std::min(c.x, std::min(c.y, c.z));
}

namespace {

Phase parsePhase(Params p) {
  Phase ph;
  const std::string t = p.choice("type", {"isotropic", "henyey-greenstein", "hg"});
  if (t == "isotropic") {
    ph.type = Phase::Type::Isotropic;
  } else {
    ph.type = Phase::Type::HenyeyGreenstein;
    ph.g = p.real("g", std::nullopt, Interval::open(-1, 1));
  }
  p.finish();
  return ph;
}

Light parseLight(Params p) {
  Light l;
  const std::string t = p.choice("type", {"point", "spot", "directional"});
  const Interval positive = Interval::atLeast(0);
  if (t == "point" || t == "spot") {
    l.type = t == "point" ? Light::Type::Point : Light::Type::Spot;
    l.position = p.vec3("position");
    l.intensity = p.rgb("intensity", std::nullopt, positive);
  }
  if (t == "spot") {
    const Vec3 d = p.vec3("direction");
    if (glm::length(d) == 0.0f) p.fail("direction", "must not be the zero vector");
    l.direction = glm::normalize(d);
    const float outer = p.real("outer_deg", std::nullopt, Interval{0, 180, true, false});
    const float inner = p.real("inner_deg", 0.0, Interval::closed(0, 180));
    if (inner > outer)
      p.fail("inner_deg", "value " + std::to_string(inner) + " exceeds outer_deg = " +
                              std::to_string(outer) + "; allowed: 0 <= inner_deg <= outer_deg");
    l.cosInner = std::cos(inner * kPi / 180.0f);
    l.cosOuter = std::cos(outer * kPi / 180.0f);
  }
  if (t == "directional") {
    l.type = Light::Type::Directional;
    const Vec3 d = p.vec3("direction");
    if (glm::length(d) == 0.0f) p.fail("direction", "must not be the zero vector");
    l.direction = glm::normalize(d);
    l.intensity = p.rgb("irradiance", std::nullopt, positive);
  }
  p.finish();
  return l;
}

Camera parseCamera(Params p) {
  Camera c;
  c.position = p.vec3("position");
  c.lookAt = p.vec3("look_at");
  c.up = p.vec3("up", Vec3(0, 1, 0));
  c.fovYDeg = p.real("fov_y_deg", 40.0, Interval::open(0, 180));
  c.width = int(p.integer("width", 320, Interval::closed(1, 16384)));
  c.height = int(p.integer("height", 240, Interval::closed(1, 16384)));
  c.spp = int(p.integer("spp", 1, Interval::closed(1, 1024)));
  const int k = int(std::lround(std::sqrt(double(c.spp))));
  if (k * k != c.spp)
    p.fail("spp", "value " + std::to_string(c.spp) +
                      " is not a perfect square; allowed: 1, 4, 9, 16, ... 1024 (k x k strata)");
  p.finish();
  if (c.position == c.lookAt) p.fail("look_at", "must differ from camera.position");
  if (glm::length(glm::cross(c.lookAt - c.position, c.up)) == 0.0f)
    p.fail("up", "must not be parallel to the view direction (look_at - position)");
  return c;
}

Medium parseMedium(Params p, LoadContext ctx) {
  Medium m;
  if (p.has("bounds")) {
    Params b = p.child("bounds");
    m.bounds.min = b.vec3("min");
    m.bounds.max = b.vec3("max");
    b.finish();
    if (!m.bounds.valid())
      b.fail("max", "must exceed min in every axis (min " + describeValue(b.json()["min"]) +
                        ", max " + describeValue(b.json()["max"]) + ")");
    ctx.mediumBounds = m.bounds;
  } else {
    p.allow("bounds");
  }
  {
    Params d = p.child("density");
    const std::string type = d.string("type");
    const auto& factory = densityModels().get(type, d.keyPath("type"));
    m.density = factory(d, ctx);
    d.finish();
  }
  if (!ctx.mediumBounds) {
    if (auto nb = m.density->naturalBounds())
      m.bounds = *nb;
    else
      p.fail("bounds", "required for density type '" + m.density->type() +
                           "' (expected {\"min\": [x,y,z], \"max\": [x,y,z]})");
  }
  m.resolution = p.resolution("resolution", IVec3(128));
  m.sigmaT = p.real("sigma_t", 1.0, Interval::atLeast(0));
  m.albedo = p.real("albedo", 1.0, Interval::closed(0, 1));
  if (p.has("phase"))
    m.phase = parsePhase(p.child("phase"));
  else
    p.allow("phase");
  p.finish();
  return m;
}

}  // namespace

Scene parseScene(const Json& doc, const std::filesystem::path& baseDir, const Medium* keepMedium) {
  Params root(doc, "");
  Scene s;
  s.baseDir = baseDir;
  LoadContext ctx;
  ctx.baseDir = baseDir;
  if (keepMedium) {
    s.medium = *keepMedium;
    root.allow("medium");
  } else {
    s.medium = parseMedium(root.child("medium"), ctx);
  }
  for (Params l : root.children("lights", /*required=*/true)) s.lights.push_back(parseLight(l));
  s.camera = parseCamera(root.child("camera"));
  s.background = root.rgb("background", Vec3(0.0f));
  if (root.has("objects")) {
    auto items = root.children("objects");
    if (!items.empty()) s.objects = SceneObjects::parse(std::move(items), baseDir);
  } else {
    root.allow("objects");
  }
  if (root.has("render")) {
    if (!doc["render"].is_object()) Params(doc["render"], "render");  // throws: not an object
    s.render = doc["render"];
  }
  root.allow("render");
  root.finish();
  return s;
}

Json readJsonFile(const std::string& path) {
  checkReadableFile(path, "JSON file");
  std::ifstream in(path);
  if (!in) throw IoError("cannot open '" + path + "'");
  try {
    return Json::parse(in, nullptr, true, /*ignore_comments=*/true);
  } catch (const Json::parse_error& e) {
    throw IoError("malformed JSON in '" + path + "': " + e.what());
  }
}

Scene loadScene(const std::string& path, const std::vector<std::string>& overrides) {
  Json doc = readJsonFile(path);
  for (const auto& o : overrides) applyOverride(doc, o);
  try {
    // Light paths are evaluated at the document's own time (core/animation.h).
    return parseScene(sceneAtTime(doc, documentTime(doc)),
                      std::filesystem::path(path).parent_path());
  } catch (const ConfigError& e) {
    throw ConfigError(path + ": " + e.what());
  }
}

}  // namespace scatterlab
