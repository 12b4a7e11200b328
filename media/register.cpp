#include "media/register.h"

#include <cfloat>
#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "core/objects.h"
#include "media/dense_grid.h"
#include "media/procedural.h"
#include "media/sog.h"
#include "media/vdb.h"

namespace scatterlab {
namespace {

const Interval kNonNegative = Interval::atLeast(0);

/// Every procedural model reads `time` (default 0); see docs/media.md for what moves.
float readTime(Params& p) {
  return p.real("time", 0.0);
}

/// `value` + `rate`·`time` in double, or a ConfigError naming the keys when it leaves single
/// precision (issue 37: it became inf, then an empty medium, black with exit 0, or NaN).
float densityAtTime(Params& p, const char* key, float value, float rate, float time) {
  const double v = double(value) + double(rate) * double(time);
  if (!(std::abs(v) <= double(FLT_MAX))) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "'%s' + rate x time = %g at time %g is beyond single precision; use a smaller "
                  "rate or an earlier time",
                  key, v, double(time));
    p.fail("rate", buf);
  }
  return float(v);
}

std::unique_ptr<DensityModel> makeUniform(Params& p, const LoadContext&) {
  const float value = p.real("value", std::nullopt, kNonNegative);
  const float rate = p.real("rate", 0.0);  // density change per unit time
  const float time = readTime(p);
  return std::make_unique<UniformDensity>(
      std::max(0.0f, densityAtTime(p, "value", value, rate, time)));
}

std::unique_ptr<DensityModel> makeGaussians(Params& p, const LoadContext&) {
  std::vector<GaussianBlob> blobs;
  const float time = readTime(p);
  for (Params b : p.children("blobs", /*required=*/true)) {
    GaussianBlob g;
    // Blobs drift with their velocity (world units per unit time), in double: the centre is a
    // point of the scene (a sample point of gaussian-centres, the origin of shadow rays), so it
    // stays within the coordinate bound Embree traces (kMaxCoordinate).
    const glm::dvec3 c =
        glm::dvec3(b.vec3("center")) + glm::dvec3(b.vec3("velocity", Vec3(0.0f))) * double(time);
    for (int a = 0; a < 3; ++a)
      if (!(std::abs(c[a]) <= kMaxCoordinate)) {
        char buf[192];
        std::snprintf(buf, sizeof buf,
                      "the centre at time %g is [%g, %g, %g], beyond the coordinate bound; "
                      "allowed: every coordinate within +-%g",
                      double(time), c.x, c.y, c.z, kMaxCoordinate);
        b.fail(b.has("velocity") ? "velocity" : "center", buf);
      }
    g.center = Vec3(c);
    g.radius = b.real("radius", std::nullopt, Interval::above(0));
    g.weight = b.real("weight", 1.0, kNonNegative);
    b.finish();
    blobs.push_back(g);
  }
  return std::make_unique<GaussianDensity>(std::move(blobs));
}

std::unique_ptr<DensityModel> makeHeight(Params& p, const LoadContext& ctx) {
  const float bottom = p.real("bottom", std::nullopt, kNonNegative);
  const float top = p.real("top", std::nullopt, kNonNegative);
  const float rate = p.real("rate", 0.0);  // added to both ends per unit time
  const float time = readTime(p);
  if (!ctx.mediumBounds) p.fail("type", "'height' needs medium.bounds");
  const float bottomNow = densityAtTime(p, "bottom", bottom, rate, time);
  const float topNow = densityAtTime(p, "top", top, rate, time);
  return std::make_unique<HeightDensity>(*ctx.mediumBounds, std::max(0.0f, bottomNow),
                                         std::max(0.0f, topNow));
}

std::unique_ptr<DensityModel> makeDustyRoom(Params& p, const LoadContext& ctx) {
  DustyRoomParams d;
  d.floor = p.real("floor", d.floor, kNonNegative);
  d.ceiling = p.real("ceiling", d.ceiling, kNonNegative);
  d.amplitude = p.real("amplitude", d.amplitude, kNonNegative);
  d.frequency = p.real("frequency", d.frequency, Interval::above(0));
  d.octaves = int(p.integer("octaves", d.octaves, Interval::closed(0, 8)));
  d.seed = std::uint32_t(p.integer("seed", 0, Interval::closed(0, 4294967295.0)));
  d.time = readTime(p);
  d.wind = p.vec3("wind", d.wind);
  // The noise is looked up at x − wind·time: beyond the coordinate bound it is NaN or inf.
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(double(d.wind[a]) * double(d.time)) <= kMaxCoordinate)) {
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "wind x time = %g at time %g is beyond the coordinate bound of +-%g (the "
                    "noise would be NaN); use a smaller wind or an earlier time",
                    double(d.wind[a]) * double(d.time), double(d.time), kMaxCoordinate);
      p.fail("wind", buf);
    }
  if (!ctx.mediumBounds)
    p.fail("type", "'dusty-room' needs medium.bounds (floor = min.y, ceiling = max.y)");
  return std::make_unique<DustyRoomDensity>(*ctx.mediumBounds, d);
}

std::unique_ptr<DensityModel> makeGrid(Params& p, const LoadContext& ctx) {
  const Vec3 dv = p.vec3("dims", std::nullopt, Interval::closed(1, 4096));
  const IVec3 dims(dv);
  if (Vec3(dims) != dv)
    p.fail("dims", "expected 3 integers, got " + describeValue(p.json()["dims"]));
  if ((long long)dims.x * dims.y * dims.z > kMaxGridVoxels)
    p.fail("dims", "more than " + std::to_string(kMaxGridVoxels) + " voxels (512^3)");
  if (!ctx.mediumBounds) p.fail("type", "'grid' needs medium.bounds");
  const bool hasValues = p.has("values"), hasFile = p.has("file");
  if (hasValues == hasFile)
    p.fail("values", "give exactly one of 'values' (inline) or 'file' (raw float32)");
  DensityGrid g(*ctx.mediumBounds, dims);
  std::string source;
  if (hasValues) {
    const Json& v = p.raw("values");
    const size_t n = g.size();
    if (!v.is_array() || v.size() != n)
      p.fail("values", "expected an array of " + std::to_string(n) + " numbers (dims " +
                           std::to_string(dims.x) + "x" + std::to_string(dims.y) + "x" +
                           std::to_string(dims.z) + "), got " + describeValue(v));
    for (size_t i = 0; i < n; ++i) {
      // Stored as float: a larger double (1e300) would become inf.
      if (!v[i].is_number() || !(v[i].get<double>() >= 0) || !(v[i].get<double>() <= FLT_MAX))
        p.fail("values", "element " + std::to_string(i) + " = " + describeValue(v[i]) +
                             " is out of range; allowed: a number in [0, 3.40282e+38] (single "
                             "precision)");
      g.data()[i] = v[i].get<float>();
    }
    source = "inline values";
  } else {
    const std::string file = ctx.resolve(p.string("file")).string();
    g.data() = readRawFloats(file, dims);
    for (size_t i = 0; i < g.size(); ++i)
      if (!(g.data()[i] >= 0) || !std::isfinite(g.data()[i]))
        throw IoError("raw density file '" + file + "': value " + std::to_string(g.data()[i]) +
                      " at index " + std::to_string(i) + " is not a finite number >= 0");
    source = file;
  }
  return std::make_unique<DenseGridDensity>(std::move(g), source);
}

std::unique_ptr<DensityModel> makeVdb(Params& p, const LoadContext& ctx) {
  const std::string file = ctx.resolve(p.string("file")).string();
  const std::string grid = p.string("grid", std::string("density"));
  try {
    return VdbDensity::load(file, grid);
  } catch (const ConfigError& e) {
    // Name the scene key too: the grid is chosen by `grid`.
    throw ConfigError("'" + p.keyPath("grid") + "': " + e.what());
  }
}

std::unique_ptr<DensityModel> makeSog(Params& p, const LoadContext& ctx) {
  const bool hasFile = p.has("file"), hasFrames = p.has("frames");
  if (hasFile == hasFrames)
    p.fail("file",
           "give exactly one of 'file' (one .sog model) or 'frames' (a list of .sog "
           "files, one per frame, chosen by 'time' and 'fps')");
  if (hasFile) {
    const std::string file = ctx.resolve(p.string("file")).string();
    return std::make_unique<SogDensity>(readSog(file), file);
  }
  const Json& frames = p.raw("frames");
  if (!frames.is_array() || frames.empty())
    p.fail("frames", "expected a non-empty array of file names, got " + describeValue(frames));
  for (size_t i = 0; i < frames.size(); ++i)
    if (!frames[i].is_string())
      p.fail("frames", "element " + std::to_string(i) + " = " + describeValue(frames[i]) +
                           " is not a file name (string)");
  const double time = p.number("time", 0.0, Interval::atLeast(0));
  const double fps = p.number("fps", 24.0, Interval::above(0));
  // Frame f covers times [f/fps, (f+1)/fps); past the last frame the last one holds.
  const size_t frame = std::min(frames.size() - 1, size_t(std::floor(time * fps + 1e-9)));
  const std::string file = ctx.resolve(frames[frame].get<std::string>()).string();
  return std::make_unique<SogDensity>(readSog(file),
                                      file + " (frame " + std::to_string(frame) + ")");
}

}  // namespace

void registerMediaModels() {
  ensureOpenVdbInitialized();
  auto& r = densityModels();
  r.add("uniform", makeUniform);
  r.add("gaussians", makeGaussians);
  r.add("height", makeHeight);
  r.add("grid", makeGrid);
  r.add("vdb", makeVdb);
  r.add("sog", makeSog);
  r.add("dusty-room", makeDustyRoom);
}

}  // namespace scatterlab
