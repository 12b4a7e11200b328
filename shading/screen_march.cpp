#include "shading/screen_march.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "core/error.h"

namespace scatterlab {

namespace {

// The keys of `jittered-march` and `froxel`, each family's table beside its parser.

const std::vector<KeyDoc>& jitteredMarchKeys() {
  static const std::vector<KeyDoc> keys = {
      {"steps", "int", "32", "1…4096",
       "view-ray steps per ray (its piece inside the medium box, up to the first surface), "
       "whatever its length",
       "2"},
      {"jitter", "string", "ign", "none, ign, blue-noise",
       "per-pixel offset of the samples inside their steps: the middle, interleaved gradient "
       "noise (Jimenez 2014), or a 64×64 tileable void-and-cluster blue-noise table",
       R"("blue-noise")"},
      {"downsample", "int", "1", "1, 2, 4",
       "the march runs at 1/downsample of the image resolution per axis; depth-aware "
       "(bilateral) upsampling to the full image",
       "2"},
  };
  return keys;
}

void parseJitteredMarch(Params& p, const Scene&, PipelineSettings& settings) {
  JitteredMarchSettings s;
  s.steps = int(p.integer("steps", 32, Interval::closed(1, 4096)));
  const std::string j = p.choice("jitter", {"none", "ign", "blue-noise"}, "ign");
  s.jitter = j == "none" ? Jitter::None : j == "ign" ? Jitter::Ign : Jitter::BlueNoise;
  s.downsample = int(p.integer("downsample", 1, Interval::closed(1, 4)));
  if (s.downsample == 3) p.fail("downsample", "must be 1, 2 or 4 (got 3)");
  settings.integratorKeys.set(s);
}

const std::vector<KeyDoc>& froxelKeys() {
  static const std::vector<KeyDoc> keys = {
      {"froxel_grid", "[nx,ny,nz]", "[160, 90, 64]", "1…1024 per axis, at most 2²⁴ froxels",
       "froxels across, down, and depth slices of the camera-frustum grid", "[4, 3, 2]"},
      {"depth_distribution", "string", "exponential", "exponential, linear",
       "depth slice k covers view depths near·(far/near)^(k/nz) … (k+1) (exponential) or "
       "equal steps (linear)",
       R"("linear")"},
      {"near", "number", "the medium box's nearest view depth (at least far/1000)", "> 0, < far",
       "view depth of the first slice's near face", "0.01"},
      {"far", "number", "the medium box's farthest view depth", "> near",
       "view depth of the last slice's far face; medium beyond it is not seen", "100"},
      {"light_transmittance", "string", "traced", "traced, map",
       "transmittance to each light at a froxel: traced through the density volume with step "
       "delta1, or looked up trilinearly in a per-light map over the medium box",
       R"("map")"},
      {"transmittance_map_resolution", "int", "64", "2…512",
       "voxels per axis of each light's transmittance map (light_transmittance = map)", "4"},
  };
  return keys;
}

void parseFroxel(Params& p, const Scene&, PipelineSettings& settings) {
  FroxelSettings s;
  p.allow("froxel_grid");  // read below when given; its default otherwise
  if (p.has("froxel_grid")) {
    const Json& g = p.raw("froxel_grid");
    if (!g.is_array() || g.size() != 3)
      p.fail("froxel_grid", "must be [nx, ny, nz] (froxels across, down, and depth slices)");
    for (int a = 0; a < 3; ++a) {
      if (!g[a].is_number_integer() || g[a].get<long long>() < 1 || g[a].get<long long>() > 1024)
        p.fail("froxel_grid", "entries must be integers in 1…1024 (got " + g.dump() + ")");
      s.grid[a] = g[a].get<int>();
    }
    if (double(s.grid.x) * s.grid.y * s.grid.z > double(1 << 24))
      p.fail("froxel_grid", "has more than 2^24 froxels (" + g.dump() + ")");
  }
  s.distribution =
      p.choice("depth_distribution", {"exponential", "linear"}, "exponential") == "exponential"
          ? DepthDistribution::Exponential
          : DepthDistribution::Linear;
  // 0: the medium box's view depths (froxelSlicing), known only with the camera.
  p.allow("near");
  p.allow("far");
  s.near = p.has("near") ? p.real("near", std::nullopt, Interval::above(0)) : 0.0f;
  s.far = p.has("far") ? p.real("far", std::nullopt, Interval::above(0)) : 0.0f;
  if (s.near > 0.0f && s.far > 0.0f && !(s.far > s.near))
    p.fail("far", "must be greater than near (" + std::to_string(s.near) + ")");
  s.transmittanceMap = p.choice("light_transmittance", {"traced", "map"}, "traced") == "map";
  s.mapResolution = int(p.integer("transmittance_map_resolution", 64, Interval::closed(2, 512)));
  settings.integratorKeys.set(s);
}

}  // namespace

FroxelSlicing froxelSlicing(const Scene& scene, const FroxelSettings& s) {
  const auto [zmin, zmax] =
      Camera::viewDepthRange(scene.camera.rayGenerator(), scene.medium.bounds);
  FroxelSlicing f;
  f.slices = s.grid.z;
  f.exponential = s.distribution == DepthDistribution::Exponential;
  f.far = s.far > 0.0f ? s.far : zmax;
  if (!(f.far > 0.0f))
    throw ConfigError(
        "render.far: the medium box is behind the camera; give render.near and "
        "render.far");
  f.near = s.near > 0.0f ? s.near : std::max(zmin, f.far / 1000.0f);
  if (!(f.far > f.near))
    throw ConfigError("render.near (" + std::to_string(f.near) + ") must be below render.far (" +
                      std::to_string(f.far) + ")");
  return f;
}

namespace {

std::string imageSize(const Camera& c) {
  return std::to_string(c.width) + "x" + std::to_string(c.height) + " pixels";
}

// The competitors step a fixed count per ray and trace the lights at each step (issue 26:
// renders of hours or days were accepted): their work and host arrays for the render plan.

StageWork jitteredMarchWork(const Scene& scene, const PipelineSettings& settings) {
  const auto& s = settings.integratorKeys.get<JitteredMarchSettings>();
  const Camera& c = scene.camera;
  const int ds = s.downsample;
  const double low = std::ceil(double(c.width) / ds) * std::ceil(double(c.height) / ds);
  const double terms = low * s.steps;
  return {.viewTerms = terms,
          .termsKey = "steps",
          .termsHow = formatCount(low) + " rays (1/" + std::to_string(ds) + " of " + imageSize(c) +
                      ") x " + std::to_string(s.steps) + " steps",
          .lightPoints = terms,
          .lightWhat = "at every one of " + formatCount(terms) + " view steps"};
}

StageWork froxelWork(const Scene& scene, const PipelineSettings& settings) {
  const auto& s = settings.integratorKeys.get<FroxelSettings>();
  const IVec3 g = s.grid;
  const double froxels = double(g.x) * g.y * g.z;
  StageWork w;
  // The froxel volume (in-scattered RGB + transmittance) and the per-light transmittance maps.
  w.cpuArrays.push_back({{"froxel_grid"},
                         "the froxel volume of " + std::to_string(g.x) + "x" + std::to_string(g.y) +
                             "x" + std::to_string(g.z) + " froxels",
                         froxels * (sizeof(Vec3) + sizeof(float))});
  if (s.transmittanceMap) {
    const double n = std::pow(double(s.mapResolution), 3.0);
    w.lightPoints = n;
    w.lightWhat = "at every one of " + formatCount(n) + " voxels of the transmittance maps";
    w.cpuArrays.push_back({{"transmittance_map_resolution"},
                           std::to_string(scene.lights.size()) + " transmittance maps of " +
                               std::to_string(s.mapResolution) + "^3",
                           double(scene.lights.size()) * n * sizeof(float)});
  } else {
    w.lightPoints = froxels;
    w.lightWhat = "at every one of " + formatCount(froxels) + " froxels";
  }
  return w;
}

}  // namespace

const StageDecl& jitteredMarchStage() {
  static const StageDecl d{.keys = {{jitteredMarchKeys, parseJitteredMarch}},
                           .viewMarch = true,
                           .onePerPixel = true,
                           .work = jitteredMarchWork};
  return d;
}

const StageDecl& froxelStage() {
  static const StageDecl d{.keys = {{froxelKeys, parseFroxel}},
                           .viewMarch = true,
                           .onePerPixel = true,
                           .work = froxelWork};
  return d;
}

}  // namespace scatterlab
