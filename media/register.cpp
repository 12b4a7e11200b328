#include "media/register.h"

#include <cmath>

#include "core/error.h"
#include "media/dense_grid.h"
#include "media/procedural.h"
#include "media/sog.h"
#include "media/vdb.h"

namespace scatterlab {
namespace {

const Interval kNonNegative = Interval::atLeast(0);

std::unique_ptr<DensityModel> makeUniform(Params& p, const LoadContext&) {
  return std::make_unique<UniformDensity>(p.real("value", std::nullopt, kNonNegative));
}

std::unique_ptr<DensityModel> makeGaussians(Params& p, const LoadContext&) {
  std::vector<GaussianBlob> blobs;
  for (Params b : p.children("blobs", /*required=*/true)) {
    GaussianBlob g;
    g.center = b.vec3("center");
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
  if (!ctx.mediumBounds) p.fail("type", "'height' needs medium.bounds");
  return std::make_unique<HeightDensity>(*ctx.mediumBounds, bottom, top);
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
      if (!v[i].is_number() || !(v[i].get<double>() >= 0) || !std::isfinite(v[i].get<double>()))
        p.fail("values", "element " + std::to_string(i) + " = " + describeValue(v[i]) +
                             " is not a finite number >= 0");
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
}

}  // namespace scatterlab
