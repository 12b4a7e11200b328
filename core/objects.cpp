#include "core/objects.h"

#include <embree3/rtcore.h>
#include <tiny_obj_loader.h>

#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <sstream>
#include <string>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/limits.h"

namespace scatterlab {

const std::vector<KeyDoc>& objectKeyDocs() {
  static const std::vector<KeyDoc> docs = {
      {"type", "string", "required", "`sphere`, `box`, `mesh`", "what the object is"},
      {"albedo", "number or [r,g,b]", "[0.8,0.8,0.8] (mesh: the .mtl's Kd where present)",
       "[0, 1] per channel", "Lambertian albedo; 0 is a pure (black) occluder"},
      {"center", "[x,y,z]", "required (sphere)", "center ± radius within ±1e15", "sphere centre"},
      {"radius", "number", "required (sphere)", "> 0", "sphere radius"},
      {"min", "[x,y,z]", "required (box)", "within ±1e15, < max per axis", "box corner"},
      {"max", "[x,y,z]", "required (box)", "within ±1e15, > min per axis", "box corner"},
      {"file", "string", "required (mesh)", "a readable Wavefront OBJ with ≥ 1 triangle",
       "mesh file, relative to the scene file; polygons are triangulated"},
      {"transform", "object", "identity (mesh)", "`translate`, `rotate_deg`, `scale`",
       "object to world: x' = translate + Rz·Ry·Rx·(scale ⊙ x)"},
  };
  return docs;
}

namespace {

/// Albedo of each primitive of one Embree geometry: one value, or one per triangle.
struct GeometryAlbedo {
  std::vector<Vec3> perPrim;
  /// Shading normals, 3 per triangle (the OBJ's `vn`), or empty: flat shading.
  std::vector<Vec3> normals;
  Vec3 at(unsigned prim) const { return perPrim.size() == 1 ? perPrim[0] : perPrim[prim]; }
};

/// A vec3 whose components must be finite (Params::vec3 checks only the range).
Vec3 finiteVec3(Params& p, const std::string& key, std::optional<Vec3> def = std::nullopt) {
  const Vec3 v = p.vec3(key, def);
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(v[a])) p.fail(key, "components must be finite numbers");
  return v;
}

/// "%.6g" of a number, for messages.
std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

std::string point(const glm::dvec3& v) {
  // Appended piecewise: GCC 12 reports a false -Wrestrict for "[" + std::string.
  std::string s("[");
  s += num(v.x);
  s += ", ";
  s += num(v.y);
  s += ", ";
  s += num(v.z);
  s += "]";
  return s;
}

/// Whether every coordinate of `v` lies within +-kMaxCoordinate (false for NaN).
bool withinBound(const glm::dvec3& v) {
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(v[a]) <= kMaxCoordinate)) return false;
  return true;
}

/// Fails `key` when a point of the object (`what`, e.g. "the sphere's extent") lies beyond the
/// coordinate bound.
void checkBound(const Params& p, const std::string& key, const glm::dvec3& lo, const glm::dvec3& hi,
                const std::string& what) {
  if (!withinBound(lo) || !withinBound(hi))
    p.fail(key, what + " " + point(lo) + " - " + point(hi) + " reaches beyond +-" +
                    num(kMaxCoordinate) + "; allowed: every coordinate within +-" +
                    num(kMaxCoordinate));
}

struct Mesh {
  std::vector<Vec3> vertices;
  std::vector<glm::uvec3> triangles;
  std::vector<Vec3> albedo;   ///< one, or one per triangle
  std::vector<Vec3> normals;  ///< 3 per triangle (world space) when every corner has a `vn`
};

/// Object-to-world matrix of a mesh's `transform` (translate · Rz · Ry · Rx · scale).
glm::mat4 parseTransform(Params t) {
  const Vec3 translate = finiteVec3(t, "translate", Vec3(0.0f));
  const Vec3 rot = finiteVec3(t, "rotate_deg", Vec3(0.0f));
  Vec3 scale(1.0f);
  if (t.has("scale")) {
    const Json& s = t.raw("scale");
    if (s.is_number()) {
      scale = Vec3(t.real("scale", std::nullopt, Interval::above(0)));
    } else {
      scale = t.vec3("scale", std::nullopt, Interval::above(0));
    }
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(scale[a])) t.fail("scale", "must be finite");
  }
  t.finish();
  glm::mat4 m = glm::translate(glm::mat4(1.0f), translate);
  m = glm::rotate(m, glm::radians(rot.z), Vec3(0, 0, 1));
  m = glm::rotate(m, glm::radians(rot.y), Vec3(0, 1, 0));
  m = glm::rotate(m, glm::radians(rot.x), Vec3(1, 0, 0));
  return glm::scale(m, scale);
}

/// Reads every `mtllib` of an OBJ through the same checks as every other file a scene names
/// (checkReadableFile: a regular file, not /dev/zero or a FIFO; its size against the memory
/// limit) instead of tinyobjloader's MaterialFileReader, which opens any path unchecked. Names
/// are relative to the OBJ's directory. A missing .mtl stays what tinyobjloader makes it: a
/// warning and the default albedo.
class CheckedMaterialReader : public tinyobj::MaterialReader {
 public:
  CheckedMaterialReader(std::filesystem::path dir, std::string key)
      : dir_(std::move(dir)), key_(std::move(key)) {}
  bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                  std::map<std::string, int>* matMap, std::string* warn,
                  std::string* err) override {
    const std::filesystem::path file =
        std::filesystem::path(name).is_absolute() ? std::filesystem::path(name) : dir_ / name;
    std::error_code ec;
    if (!std::filesystem::exists(std::filesystem::symlink_status(file, ec))) {
      if (warn) *warn += "material library '" + file.string() + "' not found\n";
      return false;
    }
    try {
      checkReadableFile(file.string(), "material library (.mtl)");
    } catch (const IoError& e) {
      throw IoError("'" + key_ + "': " + e.what());
    }
    const std::uintmax_t size = std::filesystem::file_size(file, ec);
    if (ec) throw IoError("'" + key_ + "': cannot read '" + file.string() + "': " + ec.message());
    // Parsed materials (name, strings, numbers) take a few times the text's bytes.
    checkMemory(
        key_,
        "the material library '" + file.string() + "' (" + formatBytes(double(size)) + ", parsed)",
        4.0 * double(size));
    std::ifstream in(file);
    if (!in) throw IoError("'" + key_ + "': cannot open '" + file.string() + "'");
    // tinyobjloader reads "inf" or "nan" as 0 without a word: every Kd must be three finite
    // numbers (their range is checked with the material's name, loadMesh).
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      std::istringstream words(line);
      std::string tag;
      if (!(words >> tag) || tag != "Kd") continue;
      std::string v;
      int count = 0;
      bool finite = true;
      while (words >> v) {
        char* end = nullptr;
        const double x = std::strtod(v.c_str(), &end);
        finite = finite && end != v.c_str() && *end == 0 && std::isfinite(x);
        ++count;
      }
      if (!finite || count != 3)
        throw IoError("'" + key_ + "': '" + file.string() + "' line " + std::to_string(n) + ": '" +
                      line.substr(0, 80) +
                      "' is not Kd and three finite numbers (an albedo in [0, 1] per channel)");
    }
    in.clear();
    in.seekg(0);
    tinyobj::LoadMtl(matMap, materials, &in, warn, err);
    return true;
  }

 private:
  std::filesystem::path dir_;
  std::string key_;
};

/// Checks an OBJ's lines before tinyobjloader reads them: it reads "nan" as 0 without a word,
/// so every vertex coordinate must be a finite number, and it reads indices with atoi, so a face
/// index beyond int (4294967297 wrapped to 1) is an error here, naming the line.
void scanObj(const std::filesystem::path& file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  const auto where = [&](long long n) {
    return key + ": line " + std::to_string(n) + " of '" + file.string() + "': ";
  };
  for (long long n = 1; std::getline(in, line); ++n) {
    if (line.size() < 2 || (line[1] != ' ' && line[1] != '\t')) continue;
    if (line[0] == 'v') {
      const char* c = line.c_str() + 1;
      for (int k = 0; k < 3; ++k) {
        char* end = nullptr;
        const double v = std::strtod(c, &end);
        if (end == c || !std::isfinite(v))
          throw IoError(where(n) + "vertex coordinate " + std::to_string(k + 1) +
                        " is not a finite number ('" + line + "')");
        c = end;
      }
    } else if (line[0] == 'f') {
      // Tokens v, v/vt, v//vn, v/vt/vn: every number within int (1-based, or negative for
      // relative indices); whether the vertex exists is checked after parsing.
      for (const char* c = line.c_str() + 1; *c;) {
        if (*c == '-' || *c == '+' || (*c >= '0' && *c <= '9')) {
          char* end = nullptr;
          errno = 0;
          const long long v = std::strtoll(c, &end, 10);
          if (errno == ERANGE || v > INT_MAX || v < -INT_MAX)
            throw IoError(where(n) + "face index " + std::string(c, std::size_t(end - c)) +
                          " is out of range; allowed: 1 ... the number of vertices, or -1 ... "
                          "-(that number) relative to the last ('" +
                          line.substr(0, 200) + "')");
          c = end == c ? c + 1 : end;
        } else {
          ++c;
        }
      }
    }
  }
}

Mesh loadMesh(Params& p, const std::filesystem::path& baseDir, std::optional<Vec3> albedo) {
  const std::string rel = p.string("file");
  const std::filesystem::path file =
      std::filesystem::path(rel).is_absolute() ? std::filesystem::path(rel) : baseDir / rel;
  // Quoted, as Params::fail does (appended: GCC 12's -Wrestrict misfires on "'" + s + "'").
  std::string key = "'";
  key += p.keyPath("file");
  key += "'";
  try {
    checkReadableFile(file.string(), "OBJ mesh");
  } catch (const IoError& e) {
    throw IoError(key + ": " + e.what());
  }
  glm::mat4 m(1.0f);
  if (p.has("transform"))
    m = parseTransform(p.child("transform"));
  else
    p.allow("transform");

  scanObj(file, key);
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  std::ifstream objIn(file);
  if (!objIn) throw IoError(key + ": cannot open '" + file.string() + "'");
  CheckedMaterialReader mtl(file.parent_path(), p.keyPath("file"));
  if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &objIn, &mtl,
                        /*triangulate=*/true, /*default_vcols_fallback=*/false) ||
      !err.empty())
    throw IoError(key + ": malformed OBJ '" + file.string() + "': " + err);
  // A material's Kd is the triangles' albedo unless the scene gives one: outside [0, 1] or not
  // finite it is an error naming the material, as a scene albedo would be (issue 37: it was
  // clamped silently).
  if (!albedo)
    for (const tinyobj::material_t& mat : materials)
      for (int c = 0; c < 3; ++c)
        if (!(mat.diffuse[c] >= 0.0f && mat.diffuse[c] <= 1.0f)) {
          char kd[96];
          std::snprintf(kd, sizeof kd, "%g %g %g", double(mat.diffuse[0]), double(mat.diffuse[1]),
                        double(mat.diffuse[2]));
          throw IoError(key + ": material '" + mat.name + "' of '" + file.string() + "' has Kd " +
                        kd + ", outside [0, 1] per channel (an albedo); fix the .mtl or give '" +
                        p.keyPath("albedo") + "'");
        }
  Mesh mesh;
  const std::size_t nv = attrib.vertices.size() / 3;
  mesh.vertices.reserve(nv);
  for (std::size_t i = 0; i < nv; ++i) {
    const Vec3 v(attrib.vertices[3 * i], attrib.vertices[3 * i + 1], attrib.vertices[3 * i + 2]);
    // The transform in double: a far translate or a huge scale must not overflow first.
    const glm::dvec3 w = glm::dvec3(glm::dmat4(m) * glm::dvec4(glm::dvec3(v), 1.0));
    if (!withinBound(w))
      throw IoError(key + ": vertex " + std::to_string(i + 1) + " of '" + file.string() + "' " +
                    point(glm::dvec3(v)) + " lies at " + point(w) +
                    (p.has("transform") ? " after the transform" : "") + ", beyond +-" +
                    num(kMaxCoordinate) + "; allowed: every coordinate within +-" +
                    num(kMaxCoordinate));
    mesh.vertices.push_back(Vec3(w));
  }
  bool anyMaterial = false, allNormals = !attrib.normals.empty();
  std::vector<Vec3> perTri;
  const glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(m)));
  for (const auto& shape : shapes) {
    const auto& idx = shape.mesh.indices;
    std::size_t off = 0;
    for (std::size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f) {
      const unsigned n = shape.mesh.num_face_vertices[f];
      if (n == 3) {
        glm::uvec3 tri;
        for (int k = 0; k < 3; ++k) {
          const int vi = idx[off + k].vertex_index;
          if (vi < 0 || std::size_t(vi) >= nv)
            throw IoError(key + ": face " + std::to_string(f + 1) + " of '" + file.string() +
                          "' refers to a vertex that does not exist");
          tri[k] = unsigned(vi);
          const int ni = idx[off + k].normal_index;
          if (ni < 0 || std::size_t(3 * ni + 2) >= attrib.normals.size()) {
            allNormals = false;
          } else if (allNormals) {
            const Vec3 n = normalMatrix * Vec3(attrib.normals[3 * ni], attrib.normals[3 * ni + 1],
                                               attrib.normals[3 * ni + 2]);
            const float len = glm::length(n);
            if (!(len > 0.0f) || !std::isfinite(len))
              allNormals = false;
            else
              mesh.normals.push_back(n / len);
          }
        }
        mesh.triangles.push_back(tri);
        const int mat = f < shape.mesh.material_ids.size() ? shape.mesh.material_ids[f] : -1;
        Vec3 kd(0.8f);
        if (mat >= 0 && std::size_t(mat) < materials.size()) {
          kd =
              Vec3(materials[mat].diffuse[0], materials[mat].diffuse[1], materials[mat].diffuse[2]);
          anyMaterial = true;
        }
        perTri.push_back(kd);
      }
      off += n;
    }
  }
  if (mesh.triangles.empty())
    throw IoError(key + ": '" + file.string() +
                  "' holds no triangles (faces with 3 or more "
                  "vertices)");
  if (!allNormals) mesh.normals.clear();
  if (albedo)
    mesh.albedo = {*albedo};
  else if (anyMaterial)
    mesh.albedo = std::move(perTri);
  else
    mesh.albedo = {Vec3(0.8f)};
  return mesh;
}

}  // namespace

struct SceneObjects::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<GeometryAlbedo> albedo;  ///< by Embree geometry id
  std::vector<ObjectInfo> info;
  std::vector<ObjectShape> shapes;
  long long triangles = 0;
  Box bounds{Vec3(kInfinity), Vec3(-kInfinity)};
  float eps = 1e-4f;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  void check(const char* what) const {
    const RTCError e = rtcGetDeviceError(device);
    if (e != RTC_ERROR_NONE)
      throw Error(std::string("Embree: ") + what + " failed (error " + std::to_string(int(e)) +
                  ")");
  }

  void grow(ObjectInfo& o, const Vec3& p) {
    o.bounds.min = glm::min(o.bounds.min, p);
    o.bounds.max = glm::max(o.bounds.max, p);
  }

  void addTriangles(const std::vector<Vec3>& v, const std::vector<glm::uvec3>& tris,
                    std::vector<Vec3> alb, ObjectInfo& o, std::vector<Vec3> normals = {}) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), v.size()));
    auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), tris.size()));
    check("allocating a mesh");
    for (std::size_t i = 0; i < v.size(); ++i) {
      vb[3 * i] = v[i].x;
      vb[3 * i + 1] = v[i].y;
      vb[3 * i + 2] = v[i].z;
      grow(o, v[i]);
    }
    for (std::size_t i = 0; i < tris.size(); ++i)
      for (int k = 0; k < 3; ++k) ib[3 * i + k] = tris[i][k];
    const unsigned id = commit(g, std::move(alb));
    albedo[id].normals = std::move(normals);
    o.triangles = (long long)tris.size();
    triangles += o.triangles;
  }

  unsigned commit(RTCGeometry g, std::vector<Vec3> alb) {
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    check("building a geometry");
    if (albedo.size() <= id) albedo.resize(id + 1);
    albedo[id].perPrim = std::move(alb);
    return id;
  }
};

SceneObjects::SceneObjects(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SceneObjects::~SceneObjects() = default;

std::shared_ptr<const SceneObjects> SceneObjects::parse(std::vector<Params> items,
                                                        const std::filesystem::path& baseDir) {
  auto impl = std::make_unique<Impl>();
  impl->device = rtcNewDevice(nullptr);
  if (!impl->device)
    throw Error("Embree: cannot create a device (error " +
                std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
  impl->scene = rtcNewScene(impl->device);
  rtcSetSceneBuildQuality(impl->scene, RTC_BUILD_QUALITY_HIGH);
  rtcSetSceneFlags(impl->scene, RTC_SCENE_FLAG_ROBUST);
  for (Params& p : items) {
    ObjectInfo o;
    o.bounds = Box{Vec3(kInfinity), Vec3(-kInfinity)};
    o.type = p.choice("type", {"sphere", "box", "mesh"});
    std::optional<Vec3> albedo;
    if (p.has("albedo")) albedo = p.rgb("albedo", std::nullopt, Interval::closed(0, 1));
    ObjectShape shape;
    if (o.type == "sphere") {
      const Vec3 c = finiteVec3(p, "center");
      const double r = p.number("radius", std::nullopt, Interval::above(0));
      if (!std::isfinite(float(r))) p.fail("radius", "must be finite (in single precision)");
      checkBound(p, withinBound(glm::dvec3(c)) ? "radius" : "center", glm::dvec3(c) - r,
                 glm::dvec3(c) + r, "the sphere's extent (center +- radius)");
      RTCGeometry g = rtcNewGeometry(impl->device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
      auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
          g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
      impl->check("allocating a sphere");
      vb[0] = c.x;
      vb[1] = c.y;
      vb[2] = c.z;
      vb[3] = float(r);
      impl->commit(g, {albedo.value_or(Vec3(0.8f))});
      shape.kind = ObjectShape::Kind::Sphere;
      shape.center = c;
      shape.radius = float(r);
      shape.albedo = {albedo.value_or(Vec3(0.8f))};
      impl->grow(o, c - Vec3(float(r)));
      impl->grow(o, c + Vec3(float(r)));
    } else if (o.type == "box") {
      const Vec3 lo = finiteVec3(p, "min"), hi = finiteVec3(p, "max");
      if (!(hi.x > lo.x && hi.y > lo.y && hi.z > lo.z))
        p.fail("max", "must exceed min in every axis (min " + describeValue(p.json()["min"]) +
                          ", max " + describeValue(p.json()["max"]) + ")");
      checkBound(p, "max", glm::dvec3(lo), glm::dvec3(hi), "the box");
      std::vector<Vec3> v;
      for (int i = 0; i < 8; ++i)
        v.push_back(Vec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z));
      const std::vector<glm::uvec3> tris = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                            {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                            {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
      impl->addTriangles(v, tris, {albedo.value_or(Vec3(0.8f))}, o);
      shape.vertices = std::move(v);
      shape.triangles = tris;
      shape.albedo = {albedo.value_or(Vec3(0.8f))};
    } else {
      Mesh mesh = loadMesh(p, baseDir, albedo);
      impl->addTriangles(mesh.vertices, mesh.triangles, mesh.albedo, o, mesh.normals);
      shape.vertices = std::move(mesh.vertices);
      shape.triangles = std::move(mesh.triangles);
      shape.albedo = std::move(mesh.albedo);
      shape.normals = std::move(mesh.normals);
    }
    impl->shapes.push_back(std::move(shape));
    p.finish();
    impl->bounds.min = glm::min(impl->bounds.min, o.bounds.min);
    impl->bounds.max = glm::max(impl->bounds.max, o.bounds.max);
    impl->info.push_back(o);
  }
  rtcCommitScene(impl->scene);
  impl->check("building the BVH");
  if (!impl->info.empty()) {
    const Vec3 far = glm::max(glm::abs(impl->bounds.min), glm::abs(impl->bounds.max));
    impl->eps = 2e-5f * std::max(std::max(far.x, far.y), std::max(far.z, 1e-3f)) +
                1e-5f * glm::length(impl->bounds.extent());
  }
  return std::shared_ptr<const SceneObjects>(new SceneObjects(std::move(impl)));
}

const std::vector<ObjectInfo>& SceneObjects::objects() const {
  return impl_->info;
}
const std::vector<ObjectShape>& SceneObjects::shapes() const {
  return impl_->shapes;
}
long long SceneObjects::triangles() const {
  return impl_->triangles;
}
Box SceneObjects::bounds() const {
  return impl_->bounds;
}
float SceneObjects::epsilon() const {
  return impl_->eps;
}

namespace {

/// What Embree's `ray.valid()` asserts (kernels/common/ray.h), checked before every query so
/// that no ray aborts the process: origin within +-FLT_LARGE (1.844e18), a finite direction,
/// tnear and tfar not NaN (tfar may be +inf).
bool traceable(const Vec3& o, const Vec3& d, float tmin, float tmax) {
  constexpr float kLarge = 1.8e18f;
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(o[a]) <= kLarge) || !(std::abs(d[a]) <= kLarge)) return false;
  return !std::isnan(tmin) && !std::isnan(tmax);
}

}  // namespace

bool SceneObjects::intersect(const Ray& r, float tmin, float tmax, SurfaceHit& hit) const {
  if (impl_->info.empty() || !traceable(r.origin, r.dir, tmin, tmax)) return false;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  rh.ray.org_x = r.origin.x;
  rh.ray.org_y = r.origin.y;
  rh.ray.org_z = r.origin.z;
  rh.ray.dir_x = r.dir.x;
  rh.ray.dir_y = r.dir.y;
  rh.ray.dir_z = r.dir.z;
  rh.ray.tnear = tmin;
  rh.ray.tfar = tmax;
  rh.ray.time = 0.0f;
  rh.ray.mask = ~0u;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  hit.t = rh.ray.tfar;
  hit.position = r.at(hit.t);
  Vec3 n(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  const float len = glm::length(n);
  n = len > 0.0f ? n / len : -r.dir;
  hit.normal = glm::dot(n, r.dir) > 0.0f ? -n : n;
  const GeometryAlbedo& g = impl_->albedo[rh.hit.geomID];
  hit.albedo = g.at(rh.hit.primID);
  hit.shading = hit.normal;
  if (!g.normals.empty()) {
    const Vec3* c = &g.normals[3 * std::size_t(rh.hit.primID)];
    const Vec3 ns = (1.0f - rh.hit.u - rh.hit.v) * c[0] + rh.hit.u * c[1] + rh.hit.v * c[2];
    const float len = glm::length(ns);
    if (len > 0.0f) hit.shading = glm::dot(ns, hit.normal) < 0.0f ? -ns / len : ns / len;
  }
  hit.object = int(rh.hit.geomID);
  return true;
}

bool SceneObjects::occluded(const Vec3& origin, const Vec3& dir, float tmin, float tmax) const {
  if (impl_->info.empty() || !(tmax > tmin) || !traceable(origin, dir, tmin, tmax)) return false;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay ray;
  ray.org_x = origin.x;
  ray.org_y = origin.y;
  ray.org_z = origin.z;
  ray.dir_x = dir.x;
  ray.dir_y = dir.y;
  ray.dir_z = dir.z;
  ray.tnear = tmin;
  ray.tfar = tmax;
  ray.time = 0.0f;
  ray.mask = ~0u;
  ray.id = 0;
  ray.flags = 0;
  rtcOccluded1(impl_->scene, &ctx, &ray);
  return ray.tfar < 0.0f;  // Embree sets tfar = -inf on a hit
}

}  // namespace scatterlab
