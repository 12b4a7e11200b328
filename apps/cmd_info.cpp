#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "api/scatterlab.h"
#include "apps/commands.h"
#include "apps/info.h"
#include "core/atomic_file.h"
#include "core/quick_look.h"
#ifdef SCATTERLAB_HAS_GPU
#include "gpu/context.h"
#endif
#include "media/sog.h"
#include "media/vdb.h"

namespace scatterlab::cli {

namespace {

const char* lightType(const Light& l) {
  return l.type == Light::Type::Point  ? "point"
         : l.type == Light::Type::Spot ? "spot"
                                       : "directional";
}

/// The keyframed path of lights[i] in the scene document, if it has one: its key count and time
/// span (the parsed light is at the scene's time).
std::optional<std::pair<std::size_t, std::pair<double, double>>> lightPath(const Json& doc,
                                                                           std::size_t i) {
  if (!doc.contains("lights") || !doc["lights"].is_array() || i >= doc["lights"].size())
    return std::nullopt;
  const Json& l = doc["lights"][i];
  if (!l.is_object() || !l.contains("path") || !l["path"].is_array() || l["path"].empty())
    return std::nullopt;
  const Json& p = l["path"];
  return std::pair{p.size(), std::pair{p.front().value("t", 0.0), p.back().value("t", 0.0)}};
}

/// One light as `info` prints it: what its type has (a point light has no direction, a
/// directional one no position), the spot's cone, and a keyframed path.
std::string lightLine(const Light& l, const Json& doc, std::size_t i) {
  char buf[512];
  const auto v = [&](const Vec3& x) {
    std::snprintf(buf, sizeof buf, "[%g %g %g]", x.x, x.y, x.z);
    return std::string(buf);
  };
  std::string s = lightType(l);
  if (l.type != Light::Type::Directional) s += ", position " + v(l.position);
  if (l.type != Light::Type::Point) s += ", direction " + v(l.direction);
  if (l.type == Light::Type::Spot) {
    std::snprintf(buf, sizeof buf, ", cone %g deg (full inside %g deg)",
                  glm::degrees(std::acos(double(l.cosOuter))),
                  glm::degrees(std::acos(double(l.cosInner))));
    s += buf;
  }
  s += (l.type == Light::Type::Directional ? ", irradiance " : ", intensity ") + v(l.intensity);
  if (const auto path = lightPath(doc, i)) {
    std::snprintf(buf, sizeof buf, "; keyframed path of %zu keys, t %g to %g (position at t = 0)",
                  path->first, path->second.first, path->second.second);
    s += buf;
  }
  return s;
}

}  // namespace

void printSceneInfo(const std::string& path) {
  const Scene s = loadScene(path);
  const Json doc = readSceneDocument(path);
  const Medium& m = s.medium;
  std::printf("scene %s\n", path.c_str());
  std::printf("  medium: box [%g %g %g]..[%g %g %g], %dx%dx%d voxels, sigma_t %g, albedo %g, %s\n",
              m.bounds.min.x, m.bounds.min.y, m.bounds.min.z, m.bounds.max.x, m.bounds.max.y,
              m.bounds.max.z, m.resolution.x, m.resolution.y, m.resolution.z, m.sigmaT, m.albedo,
              m.phase.type == Phase::Type::Isotropic
                  ? "isotropic phase"
                  : ("Henyey-Greenstein g=" + std::to_string(m.phase.g)).c_str());
  std::printf("  density: %s\n", m.density->describe().c_str());
  for (std::size_t i = 0; i < s.lights.size(); ++i)
    std::printf("  lights[%zu]: %s\n", i, lightLine(s.lights[i], doc, i).c_str());
  if (s.objects) {
    int i = 0;
    for (const ObjectInfo& o : s.objects->objects()) {
      std::printf("  objects[%d]: %s, bounds [%g %g %g]..[%g %g %g]", i++, o.type.c_str(),
                  o.bounds.min.x, o.bounds.min.y, o.bounds.min.z, o.bounds.max.x, o.bounds.max.y,
                  o.bounds.max.z);
      if (o.type != "sphere") std::printf(", %lld triangles", o.triangles);
      std::printf("\n");
    }
  }
  const Camera& c = s.camera;
  std::printf("  camera: [%g %g %g] -> [%g %g %g], fov_y %g deg, %dx%d\n", c.position.x,
              c.position.y, c.position.z, c.lookAt.x, c.lookAt.y, c.lookAt.z, c.fovYDeg, c.width,
              c.height);
  std::printf("  render: %s\n", s.render.dump().c_str());
  auto method = createMethod(s);  // validates the render settings
  (void)method;
}

namespace {

Json vec(const Vec3& v) {
  return {v.x, v.y, v.z};
}

/// min, max, mean per channel of RGB pixels over finite values; NaN and inf counted apart.
Json pixelStats(const std::vector<Vec3>& px) {
  Vec3 lo(kInfinity), hi(-kInfinity);
  glm::dvec3 sum(0.0), count(0.0);
  size_t nans = 0, infs = 0;
  for (const Vec3& p : px)
    for (int c = 0; c < 3; ++c) {
      if (std::isnan(p[c])) {
        ++nans;
      } else if (std::isinf(p[c])) {
        ++infs;
      } else {
        lo[c] = std::min(lo[c], p[c]);
        hi[c] = std::max(hi[c], p[c]);
        sum[c] += p[c];
        count[c] += 1.0;
      }
    }
  sum /= glm::max(count, glm::dvec3(1.0));
  return {{"min", vec(lo)},
          {"max", vec(hi)},
          {"mean", {sum.x, sum.y, sum.z}},
          {"nan", nans},
          {"inf", infs}};
}

/// The "min / max / mean" line of pixelStats(), and the count of non-finite values if any.
void printStats(const Json& st) {
  const auto v = [&](const char* k, int a) { return st[k][a].get<double>(); };
  std::printf("  min [%g %g %g]  max [%g %g %g]  mean [%g %g %g]\n", v("min", 0), v("min", 1),
              v("min", 2), v("max", 0), v("max", 1), v("max", 2), v("mean", 0), v("mean", 1),
              v("mean", 2));
  const auto nans = st["nan"].get<size_t>(), infs = st["inf"].get<size_t>();
  if (nans + infs > 0)
    std::printf("  non-finite: %zu NaN and %zu inf channel values (left out of min/max/mean)\n",
                nans, infs);
}

/// An 8-bit (or 16-bit, reduced) PNG as RGB in [0, 1], the stored (display-encoded) values.
Image readPngRgb(const std::string& path, int* bitDepth, int* colorType) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&img, path.c_str()))
    throw IoError("cannot read PNG '" + path + "': " + img.message);
  img.format = PNG_FORMAT_RGB;
  std::vector<unsigned char> buf(PNG_IMAGE_SIZE(img));
  if (!png_image_finish_read(&img, nullptr, buf.data(), 0, nullptr)) {
    png_image_free(&img);
    throw IoError("cannot read PNG '" + path + "': " + img.message);
  }
  // The header's own depth and colour type, for the description.
  FILE* f = std::fopen(path.c_str(), "rb");
  unsigned char head[26] = {};
  if (f) {
    if (std::fread(head, 1, sizeof head, f) != sizeof head) head[24] = head[25] = 0;
    std::fclose(f);
  }
  *bitDepth = head[24];
  *colorType = head[25];
  Image out(int(img.width), int(img.height));
  for (size_t i = 0; i < out.pixels().size(); ++i)
    out.pixels()[i] = Vec3(buf[3 * i], buf[3 * i + 1], buf[3 * i + 2]) / 255.0f;
  return out;
}

const char* pngColorType(int t) {
  switch (t) {
    case 0:
      return "gray";
    case 2:
      return "RGB";
    case 3:
      return "palette";
    case 4:
      return "gray + alpha";
    case 6:
      return "RGBA";
  }
  return "unknown";
}

}  // namespace

Json describeScene(const std::string& path) {
  const Scene s = loadScene(path);
  createMethod(s);  // validates the render settings
  const Medium& m = s.medium;
  const Json doc = readSceneDocument(path);
  Json lights = Json::array();
  for (std::size_t i = 0; i < s.lights.size(); ++i) {
    Json j = lightJson(s.lights[i]);
    if (const auto p = lightPath(doc, i))
      j["path"] = {{"keys", p->first}, {"t_first", p->second.first}, {"t_last", p->second.second}};
    lights.push_back(j);
  }
  const Camera& c = s.camera;
  return {{"file", path},
          {"kind", "scene"},
          {"medium",
           {{"bounds", {{"min", vec(m.bounds.min)}, {"max", vec(m.bounds.max)}}},
            {"resolution", {m.resolution.x, m.resolution.y, m.resolution.z}},
            {"sigma_t", m.sigmaT},
            {"albedo", m.albedo},
            {"phase", m.phase.type == Phase::Type::Isotropic
                          ? Json{{"type", "isotropic"}}
                          : Json{{"type", "henyey-greenstein"}, {"g", m.phase.g}}},
            {"density", {{"type", m.density->type()}, {"description", m.density->describe()}}}}},
          {"lights", lights},
          {"camera",
           {{"position", vec(c.position)},
            {"look_at", vec(c.lookAt)},
            {"up", vec(c.up)},
            {"fov_y_deg", c.fovYDeg},
            {"width", c.width},
            {"height", c.height}}},
          {"render", s.render}};
}

namespace {

std::string exrChannels(const Image& img) {
  return std::string(img.alpha().empty() ? "RGB" : "RGBA") + (img.depth().empty() ? "" : "Z");
}

}  // namespace

void printImageInfo(const std::string& path) {
  const Image img = readExr(path);
  std::printf("image %s: %dx%d %s float%s%s\n", path.c_str(), img.width(), img.height(),
              exrChannels(img).c_str(),
              img.alpha().empty() ? "" : " (A = 1 - transmittance of the view ray)",
              img.depth().empty() ? "" : " (Z = depth of the first surface along the view ray)");
  // Statistics over finite values; NaN and inf are counted, not folded in (a NaN made the
  // mean "-nan" and hid where it came from).
  printStats(pixelStats(img.pixels()));
  const ExrAttributes a = readExrAttributes(path);
  for (const auto& [name, value] : a.strings)
    std::printf("  %s: %s\n", name.c_str(), value.c_str());
  for (const auto& [name, m] : a.matrices) {
    std::printf("  %s:", name.c_str());
    for (int r = 0; r < 4; ++r)
      std::printf(" [%g %g %g %g]", m[std::size_t(4 * r)], m[std::size_t(4 * r + 1)],
                  m[std::size_t(4 * r + 2)], m[std::size_t(4 * r + 3)]);
    std::printf("\n");
  }
}

Json describeExr(const std::string& path) {
  const Image img = readExr(path);
  Json j = {{"file", path},         {"kind", "image"},        {"format", "OpenEXR"},
            {"width", img.width()}, {"height", img.height()}, {"channels", exrChannels(img)}};
  j.update(pixelStats(img.pixels()));
  const ExrAttributes a = readExrAttributes(path);
  Json attrs = Json::object();
  for (const auto& [name, value] : a.strings) attrs[name] = value;
  for (const auto& [name, m] : a.matrices) attrs[name] = m;
  j["attributes"] = attrs;
  return j;
}

void printPngInfo(const std::string& path) {
  int depth = 0, type = 0;
  const Image img = readPngRgb(path, &depth, &type);
  const Json st = pixelStats(img.pixels());
  std::printf("image %s: %dx%d PNG, %d-bit %s (display-encoded values in [0, 1])\n", path.c_str(),
              img.width(), img.height(), depth, pngColorType(type));
  printStats(st);
}

Json describePng(const std::string& path) {
  int depth = 0, type = 0;
  const Image img = readPngRgb(path, &depth, &type);
  Json j = {{"file", path},
            {"kind", "image"},
            {"format", "PNG"},
            {"width", img.width()},
            {"height", img.height()},
            {"bit_depth", depth},
            {"color_type", pngColorType(type)}};
  j.update(pixelStats(img.pixels()));
  return j;
}

Json describeVdb(const std::string& path) {
  Json grids = Json::array();
  for (const VdbGridInfo& g : inspectVdb(path)) {
    Json j = {{"name", g.name},
              {"value_type", g.valueType},
              {"class", g.gridClass},
              {"affine", g.affine},
              {"saved_as_half", g.savedAsHalf},
              {"voxel_size", {g.voxelSize.x, g.voxelSize.y, g.voxelSize.z}},
              {"active_voxels", g.activeVoxels},
              {"active_tiles", g.activeTiles},
              {"leaf_nodes", g.leafNodes},
              {"empty", g.empty}};
    if (!g.empty) {
      j["index_min"] = {g.indexMin.x, g.indexMin.y, g.indexMin.z};
      j["index_max"] = {g.indexMax.x, g.indexMax.y, g.indexMax.z};
      j["world_bounds"] = {{"min", vec(g.worldBounds.min)}, {"max", vec(g.worldBounds.max)}};
    }
    if (g.hasValueRange) j["values"] = {g.valueMin, g.valueMax};
    grids.push_back(j);
  }
  return {{"file", path}, {"kind", "OpenVDB"}, {"grids", grids}};
}

Json describeSog(const std::string& path) {
  const SogModel m = readSog(path);
  const ResidualHash& h = m.residual;
  const IVec3 n = h.dims();
  return {{"file", path},
          {"kind", "sum-of-Gaussians model"},
          {"bytes", m.fileBytes()},
          {"gaussians", m.gaussians.size()},
          {"lattice",
           {{"min", vec(h.bounds().min)}, {"max", vec(h.bounds().max)}, {"dims", {n.x, n.y, n.z}}}},
          {"residual_entries", h.size()},
          {"hash_bits", h.bits()},
          {"step", h.step()},
          {"threshold", m.threshold}};
}

/// `info --gpu`: the OpenGL device the GPU backend would use (creates the context).
void printGpuInfo() {
#ifdef SCATTERLAB_HAS_GPU
  const gpu::DeviceInfo& i = gpu::context().info();  // GpuError when there is none
  std::printf("gpu: %s\n  vendor: %s\n  renderer: %s\n  version: %s\n  glsl: %s\n",
              i.hardware ? "hardware" : "software rasteriser (--backend auto uses the CPU)",
              i.vendor.c_str(), i.renderer.c_str(), i.version.c_str(), i.glsl.c_str());
  std::printf("  egl: %s platform, %s\n", i.platform.c_str(), i.eglVendor.c_str());
#else
  throw GpuError("this scatterlab was built without the GPU backend (SCATTERLAB_GPU=OFF)");
#endif
}

void printVdbInfo(const std::string& path) {
  const auto grids = inspectVdb(path);
  std::printf("OpenVDB file %s: %zu grid(s)\n", path.c_str(), grids.size());
  for (const VdbGridInfo& g : grids) {
    std::printf("  grid '%s': %s, %s%s%s\n", g.name.c_str(), g.valueType.c_str(),
                g.gridClass.c_str(), g.savedAsHalf ? ", saved as half float" : "",
                g.affine ? "" : ", NON-AFFINE transform");
    std::printf("    voxel size   [%g %g %g]\n", g.voxelSize.x, g.voxelSize.y, g.voxelSize.z);
    if (g.empty) {
      std::printf("    (no active values)\n");
      continue;
    }
    const IVec3 d = g.indexMax - g.indexMin + 1;
    std::printf("    index box    [%d %d %d]..[%d %d %d] (%dx%dx%d)\n", g.indexMin.x, g.indexMin.y,
                g.indexMin.z, g.indexMax.x, g.indexMax.y, g.indexMax.z, d.x, d.y, d.z);
    std::printf("    world box    [%g %g %g]..[%g %g %g] (voxel cells, axis-aligned)\n",
                g.worldBounds.min.x, g.worldBounds.min.y, g.worldBounds.min.z, g.worldBounds.max.x,
                g.worldBounds.max.y, g.worldBounds.max.z);
    std::printf("    active       %llu voxels (%llu active tiles, %llu leaf nodes)\n",
                (unsigned long long)g.activeVoxels, (unsigned long long)g.activeTiles,
                (unsigned long long)g.leafNodes);
    if (g.hasValueRange)
      std::printf("    values       %g .. %g%s\n", g.valueMin, g.valueMax,
                  g.valueType.rfind("vec", 0) == 0 ? " (length)" : "");
  }
}

void printSogInfo(const std::string& path) {
  const SogModel m = readSog(path);
  const ResidualHash& h = m.residual;
  const IVec3 n = h.dims();
  std::printf("sum-of-Gaussians model %s (format version 1, %zu bytes)\n", path.c_str(),
              m.fileBytes());
  std::printf("  gaussians      %zu\n", m.gaussians.size());
  std::printf("  lattice        [%g %g %g]..[%g %g %g], %dx%dx%d\n", h.bounds().min.x,
              h.bounds().min.y, h.bounds().min.z, h.bounds().max.x, h.bounds().max.y,
              h.bounds().max.z, n.x, n.y, n.z);
  std::printf(
      "  residual hash  %zu entries (%.3f%% of the lattice), %d-bit, step %g, "
      "threshold %g\n",
      h.size(), 100.0 * double(h.size()) / (double(n.x) * n.y * n.z), h.bits(), double(h.step()),
      double(m.threshold));
}

namespace {

/// The registered methods: name, backends, one-line summary (or a JSON object of them).
void printMethods(bool json) {
  Json all = Json::object();
  for (const std::string& name : methods().names()) {
    const MethodEntry& e = methods().get(name, "method");
    Json backends = Json::array();
    if (e.runsOn(Backend::Cpu)) backends.push_back("cpu");
    if (e.runsOn(Backend::Gpu)) backends.push_back("gpu");
    all[name] = {{"summary", e.summary}, {"backends", backends}};
  }
  if (json) {
    std::printf("%s\n", all.dump(2).c_str());
    return;
  }
  for (const auto& [name, m] : all.items()) {
    std::string b;
    for (const auto& x : m["backends"]) b += (b.empty() ? "" : ", ") + x.get<std::string>();
    std::printf("%-22s %-9s %s\n", name.c_str(), b.c_str(),
                m["summary"].get<std::string>().c_str());
  }
}

/// Every render key a registered method reads, once per distinct table row (two families may
/// own a key of the same name: light-space-march's and jittered-march's `steps`), with the
/// methods that read it; or a JSON object of them (key → array of rows). KeyDoc's views point
/// at static tables.
void printKeys(bool json) {
  Json all = Json::object();
  for (const std::string& name : methods().names())
    for (const KeyDoc& row : methods().get(name, "method").keyDocs) {
      Json entry = {{"type", row.type},
                    {"default", row.def},
                    {"allowed", row.range},
                    {"meaning", row.meaning}};
      if (!row.only.empty()) entry["only"] = row.only;
      Json& rows = all[std::string(row.name)];
      if (rows.is_null()) rows = Json::array();
      auto same = std::find_if(rows.begin(), rows.end(), [&](const Json& r) {
        return r["type"] == entry["type"] && r["default"] == entry["default"] &&
               r["allowed"] == entry["allowed"] && r["meaning"] == entry["meaning"];
      });
      if (same == rows.end()) {
        entry["methods"] = Json::array();
        rows.push_back(entry);
        same = rows.end() - 1;
      }
      (*same)["methods"].push_back(name);
    }
  if (json) {
    std::printf("%s\n", all.dump(2).c_str());
    return;
  }
  for (const auto& [name, rows] : all.items())
    for (const Json& k : rows) {
      std::string m;
      for (const auto& x : k["methods"]) m += (m.empty() ? "" : ", ") + x.get<std::string>();
      const std::string only =
          k.contains("only") ? " [" + k["only"].get<std::string>() + " only]" : "";
      std::printf("render.%s (%s; default %s; allowed %s)%s\n    %s\n    read by: %s\n",
                  name.c_str(), k["type"].get<std::string>().c_str(),
                  k["default"].get<std::string>().c_str(), k["allowed"].get<std::string>().c_str(),
                  only.c_str(), k["meaning"].get<std::string>().c_str(), m.c_str());
    }
}

}  // namespace

Action addInfo(CLI::App& app) {
  auto file = std::make_shared<std::string>();
  auto gpuFlag = std::make_shared<bool>(false), jsonFlag = std::make_shared<bool>(false);
  CLI::App* c = app.add_subcommand(
      "info", "Describe a scene (.json), image (.exr, .png), volume (.vdb) or model (.sog)");
  auto methodsFlag = std::make_shared<bool>(false);
  c->add_option("file", *file, "File to describe");
  c->add_flag("--methods", *methodsFlag,
              "List the rendering methods of this build with the backends each runs on");
  auto keysFlag = std::make_shared<bool>(false);
  c->add_flag("--keys", *keysFlag,
              "List every render key the methods read: type, default, allowed values, meaning, "
              "and which methods read it (docs/scene-format.md)");
  c->add_flag("--gpu", *gpuFlag,
              "Print the OpenGL vendor, renderer and version of the GPU backend");
  c->add_flag("--json", *jsonFlag, "Print the file's facts as one JSON object (not with --gpu)");
  return [file, gpuFlag, jsonFlag, methodsFlag, keysFlag]() {
    if (*jsonFlag && *gpuFlag) throw ConfigError("info: --json describes a FILE, not --gpu");
    if (*methodsFlag) printMethods(*jsonFlag && file->empty());
    if (*keysFlag) printKeys(*jsonFlag && file->empty());
    if (*gpuFlag) printGpuInfo();
    if (file->empty()) {
      if (*gpuFlag || *methodsFlag || *keysFlag) return 0;
      throw ConfigError("info: give a FILE to describe, or --gpu, --methods or --keys");
    }
    checkReadableFile(*file);
    std::string ext = std::filesystem::path(*file).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (const InfoHandler* h = findInfoHandler(ext)) {
      if (*jsonFlag)
        std::printf("%s\n", h->describe(*file).dump(2).c_str());
      else
        h->print(*file);
      return 0;
    }
    std::string known;
    for (const auto& h : infoHandlers()) known += (known.empty() ? "" : ", ") + h.extension;
    throw IoError("info: don't know how to describe '" + *file + "'; known extensions: " + known);
  };
}

const std::vector<InfoHandler>& infoHandlers() {
  static const std::vector<InfoHandler> h = {
      {".json", "scene", printSceneInfo, describeScene},
      {".exr", "OpenEXR image", printImageInfo, describeExr},
      {".png", "PNG image", printPngInfo, describePng},
      {".vdb", "OpenVDB volume", printVdbInfo, describeVdb},
      {".sog", "sum-of-Gaussians model", printSogInfo, describeSog},
  };
  return h;
}

const InfoHandler* findInfoHandler(const std::string& ext) {
  for (const auto& h : infoHandlers())
    if (h.extension == ext) return &h;
  return nullptr;
}

}  // namespace scatterlab::cli
