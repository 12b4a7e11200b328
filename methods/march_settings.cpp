#include "methods/march_settings.h"

namespace scatterlab {

const std::vector<KeyDoc>& jitteredMarchKeys() {
  static const std::vector<KeyDoc> keys = {
      {"steps", "int", "32", "1…4096",
       "view-ray steps per ray (its piece inside the medium box, up to the first surface), "
       "whatever its length"},
      {"jitter", "string", "ign", "none, ign, blue-noise",
       "per-pixel offset of the samples inside their steps: the middle, interleaved gradient "
       "noise (Jimenez 2014), or a 64×64 tileable void-and-cluster blue-noise table"},
      {"downsample", "int", "1", "1, 2, 4",
       "the march runs at 1/downsample of the image resolution per axis; depth-aware "
       "(bilateral) upsampling to the full image"},
  };
  return keys;
}

const std::vector<KeyDoc>& froxelKeys() {
  static const std::vector<KeyDoc> keys = {
      {"froxel_grid", "[nx,ny,nz]", "[160, 90, 64]", "1…1024 per axis, at most 2²⁴ froxels",
       "froxels across, down, and depth slices of the camera-frustum grid"},
      {"depth_distribution", "string", "exponential", "exponential, linear",
       "depth slice k covers view depths near·(far/near)^(k/nz) … (k+1) (exponential) or "
       "equal steps (linear)"},
      {"near", "number", "the medium box's nearest view depth (at least far/1000)", "> 0, < far",
       "view depth of the first slice's near face"},
      {"far", "number", "the medium box's farthest view depth", "> near",
       "view depth of the last slice's far face; medium beyond it is not seen"},
      {"light_transmittance", "string", "traced", "traced, map",
       "transmittance to each light at a froxel: traced through the density volume with step "
       "delta1, or looked up trilinearly in a per-light map over the medium box"},
      {"transmittance_map_resolution", "int", "64", "2…512",
       "voxels per axis of each light's transmittance map (light_transmittance = map)"},
  };
  return keys;
}

JitteredMarchSettings parseJitteredMarch(Params& p) {
  JitteredMarchSettings s;
  s.steps = int(p.integer("steps", 32, Interval::closed(1, 4096)));
  const std::string j = p.choice("jitter", {"none", "ign", "blue-noise"}, "ign");
  s.jitter = j == "none" ? Jitter::None : j == "ign" ? Jitter::Ign : Jitter::BlueNoise;
  s.downsample = int(p.integer("downsample", 1, Interval::closed(1, 4)));
  if (s.downsample == 3) p.fail("downsample", "must be 1, 2 or 4 (got 3)");
  return s;
}

FroxelSettings parseFroxel(Params& p) {
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
  return s;
}

}  // namespace scatterlab
