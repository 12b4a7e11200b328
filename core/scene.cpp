#include "core/scene.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

#include "core/animation.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/limits.h"
#include "core/objects.h"
#include "core/quick_look.h"

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

/// Farthest a light or the camera may be from the medium: 1e6 box diagonals from its centre.
/// Beyond that single precision has nothing left of the box (and |x|² overflows near 1e19).
constexpr double kMaxDistanceInDiagonals = 1e6;

/// Largest light intensity (point, spot) or irradiance (directional) per channel. Images scale
/// with it (glow.json: the brightest pixel is ~3 x I, rbf's ~12 x I) and the intermediate sums
/// of every method must stay within single precision (3.4e38): 1e36 made 18 pixels of `exact`
/// infinite and the whole radial-blur image NaN. 1e20 leaves those sums 1e18 of headroom.
constexpr double kMaxLightIntensity = 1e20;

/// Checks that `key` (a point already read) lies within kMaxDistanceInDiagonals of the box and
/// within +-kMaxCoordinate (a box near that bound has diagonals of up to 3.5e15, so the first
/// rule alone allowed 3.5e21, beyond what Embree traces).
void checkNearMedium(const Params& p, const std::string& key, const Vec3& x, const Box& box) {
  const glm::dvec3 c = 0.5 * (glm::dvec3(box.min) + glm::dvec3(box.max));
  const double diag = glm::length(glm::dvec3(box.max) - glm::dvec3(box.min));
  const double d = glm::length(glm::dvec3(x) - c);
  if (!(d <= kMaxDistanceInDiagonals * diag)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, " is %.3g box diagonals (of %.3g) from the medium's centre",
                  d / diag, diag);
    p.fail(key, "point " + describeValue(p.json()[key]) + buf + "; allowed: at most 1e6");
  }
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(double(x[a])) <= kMaxCoordinate)) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "; allowed: every coordinate within +-%g", kMaxCoordinate);
      p.fail(key,
             "point " + describeValue(p.json()[key]) + " lies beyond the coordinate bound" + buf);
    }
}

/// A non-zero direction, normalised in double so that huge finite components do not overflow.
Vec3 direction(Params& p, const std::string& key) {
  const glm::dvec3 d(p.vec3(key));
  const double len = glm::length(d);
  if (!(len > 0.0)) p.fail(key, "must not be the zero vector");
  return Vec3(d / len);
}

Light parseLight(Params p, const Box& box) {
  Light l;
  const std::string t = p.choice("type", {"point", "spot", "directional"});
  const Interval positive = Interval::closed(0, kMaxLightIntensity);
  if (t == "point" || t == "spot") {
    l.type = t == "point" ? Light::Type::Point : Light::Type::Spot;
    l.position = p.vec3("position");
    checkNearMedium(p, "position", l.position, box);
    l.intensity = p.rgb("intensity", std::nullopt, positive);
  }
  if (t == "spot") {
    l.direction = direction(p, "direction");
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
    l.direction = direction(p, "direction");
    l.intensity = p.rgb("irradiance", std::nullopt, positive);
  }
  p.finish();
  return l;
}

Camera parseCamera(Params p, const Box& box) {
  Camera c;
  c.position = p.vec3("position");
  checkNearMedium(p, "position", c.position, box);
  c.lookAt = p.vec3("look_at");
  checkNearMedium(p, "look_at", c.lookAt, box);
  c.up = p.has("up") ? direction(p, "up") : p.vec3("up", Vec3(0, 1, 0));
  c.fovYDeg = p.real("fov_y_deg", 40.0, Interval::open(0, 180));
  c.width = int(p.integer("width", 320, Interval::closed(1, Camera::kMaxSide)));
  c.height = int(p.integer("height", 240, Interval::closed(1, Camera::kMaxSide)));
  c.spp = int(p.integer("spp", 1, Interval::closed(1, 1024)));
  // The image (RGB float + alpha) and what an output encodes from it (EXR/PNG buffers).
  checkMemory(p.keyPath("width") + "', '" + p.keyPath("height"),
              "an image of " + std::to_string(c.width) + "x" + std::to_string(c.height) +
                  " pixels (32 bytes each with alpha and output buffers)",
              double(c.width) * double(c.height) * 32.0);
  const int k = int(std::lround(std::sqrt(double(c.spp))));
  if (k * k != c.spp)
    p.fail("spp", "value " + std::to_string(c.spp) +
                      " is not a perfect square; allowed: 1, 4, 9, 16, ... 1024 (k x k strata)");
  p.finish();
  // In double, and with the tolerance Camera::frame applies in float, so that a camera this
  // accepts can always build its frame.
  const glm::dvec3 view = glm::dvec3(c.lookAt) - glm::dvec3(c.position);
  const double viewLength = glm::length(view);
  if (!(viewLength > 1e-6 * glm::length(glm::dvec3(c.position) - glm::dvec3(box.center()))) ||
      !(viewLength > 0.0) || Vec3(view) == Vec3(0.0f))
    p.fail("look_at", "must differ from camera.position (distance " + std::to_string(viewLength) +
                          " is too small for single precision)");
  if (!(glm::length(glm::cross(view / viewLength, glm::dvec3(c.up))) >= 1e-3))
    p.fail("up", "must not be parallel to the view direction (look_at - position); the angle " +
                     std::string("between them must be at least 0.06 degrees"));
  return c;
}

/// A box the maths holds in: coordinates within +-1e15 and every axis wider than 1e-6 relative
/// to its coordinates (narrower boxes leave single precision no voxels to tell apart).
void checkBox(const Params& p, const std::string& key, const Box& box) {
  const auto show = [](const Vec3& v) {
    // Appended piecewise: GCC 12 reports a false -Wrestrict for "[" + std::string.
    std::string s("[");
    s += std::to_string(v.x);
    s += ", ";
    s += std::to_string(v.y);
    s += ", ";
    s += std::to_string(v.z);
    s += "]";
    return s;
  };
  for (int a = 0; a < 3; ++a) {
    const double lo = box.min[a], hi = box.max[a];
    if (!(std::abs(lo) <= 1e15 && std::abs(hi) <= 1e15))
      p.fail(key, "medium box " + show(box.min) + " - " + show(box.max) +
                      " has coordinates beyond +-1e15");
    if (!(hi - lo >= 1e-6 * std::max(1.0, std::max(std::abs(lo), std::abs(hi)))))
      p.fail(key, "medium box " + show(box.min) + " - " + show(box.max) +
                      " is too thin: every axis must be wider than 1e-6 (relative to its " +
                      "coordinates)");
  }
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
    checkBox(b, "max", m.bounds);
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
    if (auto nb = m.density->naturalBounds()) {
      m.bounds = *nb;
      checkBox(p, "density", m.bounds);
    } else
      p.fail("bounds", "required for density type '" + m.density->type() +
                           "' (expected {\"min\": [x,y,z], \"max\": [x,y,z]})");
  }
  m.resolution = p.resolution("resolution", IVec3(128), sizeof(float), "the density volume");
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

Medium parseMediumDocument(const Json& medium, const std::filesystem::path& baseDir) {
  LoadContext ctx;
  ctx.baseDir = baseDir;
  return parseMedium(Params(medium, "medium"), ctx);
}

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
  for (Params l : root.children("lights", /*required=*/true))
    s.lights.push_back(parseLight(l, s.medium.bounds));
  s.camera = parseCamera(root.child("camera"), s.medium.bounds);
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

namespace {

/// What a file that is not JSON is, by its first bytes or else its extension: for a message
/// that says what to do instead of where the JSON parser stopped. `densityType` names the
/// medium.density type that reads such a file ("" when none does); `what` is "" when unknown.
struct ForeignFile {
  std::string what, densityType;
};

ForeignFile foreignFile(const std::string& path, std::string_view head) {
  const auto starts = [&](std::string_view magic) { return head.substr(0, magic.size()) == magic; };
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower((unsigned char)c));
  // OpenVDB: the 64-bit magic 0x56444220 ("VDB " little-endian); OpenEXR: 0x762f3101.
  if (starts(std::string_view("\x20\x42\x44\x56", 4)) || ext == ".vdb")
    return {"an OpenVDB volume", "vdb"};
  if (starts(std::string_view("\x76\x2f\x31\x01", 4)) || ext == ".exr")
    return {"an OpenEXR image", ""};
  if (starts("\x89PNG") || ext == ".png") return {"a PNG image", ""};
  if (ext == ".sog") return {"a sum-of-Gaussians model (scatterlab fit)", "sog"};
  if (ext == ".obj") return {"an OBJ mesh", ""};
  return {};
}

}  // namespace

Json readJsonFile(const std::string& path) {
  checkReadableFile(path, "JSON file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open '" + path + "'");
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw IoError("cannot read '" + path + "'");
  const std::string t = text.str();
  try {
    return parseJson(t, "'" + path + "'");
  } catch (const IoError&) {
    const ForeignFile f = foreignFile(path, t);
    if (f.what.empty()) throw;
    std::string msg = "'" + path + "' is " + f.what + ", not a scene (a JSON file)";
    if (!f.densityType.empty())
      msg += "; render it from a scene whose medium.density is {\"type\": \"" + f.densityType +
             "\", \"file\": \"" + std::filesystem::path(path).filename().string() +
             "\"} (docs/scene-format.md; data/scenes/smoke.json is one)";
    throw IoError(msg + "; `scatterlab info " + path + "` describes it");
  }
}

std::string volumeFileType(const std::string& path) {
  // Only a regular file is looked into (a FIFO or device is readJsonFile's to refuse).
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return "";
  std::string head(8, '\0');
  std::ifstream in(path, std::ios::binary);
  in.read(head.data(), std::streamsize(head.size()));
  head.resize(std::size_t(std::max<std::streamsize>(0, in.gcount())));
  return foreignFile(path, head).densityType;
}

Json readSceneDocument(const std::string& path) {
  const std::string type = volumeFileType(path);
  return type.empty() ? readJsonFile(path) : quickLookScene(path, type);
}

Scene loadScene(const std::string& path, const std::vector<std::string>& overrides) {
  Json doc = readSceneDocument(path);
  for (const auto& o : overrides) applyOverride(doc, o);
  try {
    // Light paths are evaluated at the document's own time (core/animation.h).
    return parseScene(sceneAtTime(doc, documentTime(doc)),
                      std::filesystem::path(path).parent_path());
  } catch (const ConfigError& e) {
    throw ConfigError(path + ": " + e.what());
  }
}

namespace {
Json vec3Json(const Vec3& v) {
  return Json::array({v.x, v.y, v.z});
}
}  // namespace

Json lightJson(const Light& l) {
  const auto degrees = [](float c) {
    return std::round(std::acos(std::clamp(double(c), -1.0, 1.0)) * 180.0 / 3.14159265358979323846 *
                      1e4) /
           1e4;
  };
  switch (l.type) {
    case Light::Type::Spot:
      return {{"type", "spot"},
              {"position", vec3Json(l.position)},
              {"direction", vec3Json(l.direction)},
              {"intensity", vec3Json(l.intensity)},
              {"outer_deg", degrees(l.cosOuter)},
              {"inner_deg", degrees(l.cosInner)}};
    case Light::Type::Directional:
      return {{"type", "directional"},
              {"direction", vec3Json(l.direction)},
              {"irradiance", vec3Json(l.intensity)}};
    case Light::Type::Point:
      break;
  }
  return {
      {"type", "point"}, {"position", vec3Json(l.position)}, {"intensity", vec3Json(l.intensity)}};
}

Json cameraJson(const Camera& c) {
  return {{"position", vec3Json(c.position)},
          {"look_at", vec3Json(c.lookAt)},
          {"up", vec3Json(c.up)},
          {"fov_y_deg", c.fovYDeg},
          {"width", c.width},
          {"height", c.height},
          {"spp", c.spp}};
}

}  // namespace scatterlab
