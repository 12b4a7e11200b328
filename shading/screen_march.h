#pragma once
/// What the CPU and GPU variants of the per-pixel competitors share (docs/competitors.md):
/// their settings and keys (table and parser in screen_march.cpp), the jitter patterns of
/// `jittered-march` and the depth slicing of `froxel`. The GPU shaders
/// mirror these formulas line for line (gpu/shaders/jittered_march.comp.glsl,
/// froxel_scatter.comp.glsl); tests/gpu holds them in step.

#include <cmath>
#include <vector>

#include "core/math.h"
#include "core/scene.h"
#include "core/stages.h"
#include "core/stats.h"
#include "shading/blue_noise.h"

namespace scatterlab {

/// Per-pixel ray offsets of `jittered-march` (cpu/jittered_march.h).
enum class Jitter {
  None,       ///< every sample at the middle of its step
  Ign,        ///< interleaved gradient noise (Jimenez 2014) of the pixel
  BlueNoise,  ///< a 64 x 64 tileable void-and-cluster blue-noise table (shading/blue_noise.h)
};

/// `jittered-march`'s keys (jitteredMarchStage()).
struct JitteredMarchSettings {
  int steps = 32;  ///< view-ray steps per ray, whatever its length in the medium
  Jitter jitter = Jitter::Ign;
  int downsample = 1;  ///< 1, 2 or 4: the march runs at 1/downsample of the resolution
};

/// How froxel depth slices are spaced between near and far (view depth).
enum class DepthDistribution { Exponential, Linear };

/// `froxel`'s keys (froxelStage()).
struct FroxelSettings {
  IVec3 grid{160, 90, 64};  ///< froxels across, down, and depth slices
  DepthDistribution distribution = DepthDistribution::Exponential;
  float near = 0.0f,
        far = 0.0f;  ///< view depths of the grid; 0: the medium box's (see froxelRange)
  bool transmittanceMap = false;  ///< light transmittance from a per-light map, else traced
  int mapResolution = 64;         ///< voxels per axis of each light's transmittance map
};

/// `jittered-march` (an integrator, cpu/jittered_march.h): its keys steps, jitter, downsample
/// into PipelineSettings::integratorKeys (JitteredMarchSettings); one ray per pixel.
const StageDecl& jitteredMarchStage();
/// `froxel` (an integrator, cpu/froxel.h): its keys froxel_grid, depth_distribution, near, far,
/// light_transmittance, transmittance_map_resolution (FroxelSettings); one ray per pixel.
const StageDecl& froxelStage();

/// Interleaved gradient noise (Jimenez 2014, "Next generation post processing in Call of Duty:
/// Advanced Warfare") at integer pixel (x, y): fract(52.9829189·fract(0.06711056·x +
/// 0.00583715·y)), in [0, 1).
inline float interleavedGradientNoise(int x, int y) {
  const float f = 0.06711056f * float(x) + 0.00583715f * float(y);
  const float g = 52.9829189f * (f - std::floor(f));
  return g - std::floor(g);
}

/// Relative depth scale of `jittered-march`'s bilateral upsampling: a low-res neighbour whose
/// depth differs by 5 % of the pixel's weighs e^(−1) of one at the same depth.
inline constexpr float kUpsampleDepthSigma = 0.05f;

/// The per-pixel offset in [0, 1) of the samples inside their steps: ½ without jitter.
inline float jitterOffset(Jitter j, int x, int y) {
  if (j == Jitter::None) return 0.5f;
  if (j == Jitter::Ign) return interleavedGradientNoise(x, y);
  const int n = kBlueNoiseSize;
  return blueNoiseTable()[size_t(((y % n) + n) % n) * n + ((x % n) + n) % n];
}

/// The view-depth slicing of a froxel grid: nz slices between near and far, exponential
/// (z_k = near·(far/near)^(k/nz)) or linear.
struct FroxelSlicing {
  float near = 0.0f, far = 0.0f;
  int slices = 1;
  bool exponential = true;

  /// View depth of boundary k (0 … slices; fractional k interpolates the distribution).
  float depth(float k) const {
    const float s = k / float(slices);
    return exponential ? near * std::pow(far / near, s) : near + (far - near) * s;
  }
  /// The inverse of depth(): the continuous boundary coordinate of view depth z, clamped to
  /// [0, slices].
  float coordinate(float z) const {
    if (!(z > near)) return 0.0f;
    const float s =
        exponential ? std::log(z / near) / std::log(far / near) : (z - near) / (far - near);
    return std::min(float(slices), s * float(slices));
  }
};

/// The froxel slicing of `s` for `scene`: near and far as the keys give them, else the view
/// depths of the medium box (its nearest corner or the camera, at least far/1000, and its
/// farthest corner). Throws ConfigError naming render.near / render.far when they are not in
/// order for this scene.
FroxelSlicing froxelSlicing(const Scene& scene, const FroxelSettings& s);

/// The stats of `jittered-march`, the same on every backend (st.width/height must be set):
/// steps, jitter, downsample, march_rays (low-res rays), samples_per_ray.
inline void describeJitteredMarch(RenderStats& st, const JitteredMarchSettings& s) {
  const char* names[] = {"none", "ign", "blue-noise"};
  const long long w = (st.width + s.downsample - 1) / s.downsample;
  const long long h = (st.height + s.downsample - 1) / s.downsample;
  st.extra["steps"] = s.steps;
  st.extra["jitter"] = names[int(s.jitter)];
  st.extra["downsample"] = s.downsample;
  st.extra["march_rays"] = w * h;
  st.extra["view_samples"] = w * h * s.steps;
}

/// The stats of `froxel`, the same on every backend: froxel_grid, froxels, depth_distribution,
/// light_transmittance.
inline void describeFroxel(RenderStats& st, const FroxelSettings& s) {
  st.extra["froxel_grid"] = {s.grid.x, s.grid.y, s.grid.z};
  st.extra["froxels"] = (long long)s.grid.x * s.grid.y * s.grid.z;
  st.extra["depth_distribution"] =
      s.distribution == DepthDistribution::Exponential ? "exponential" : "linear";
  st.extra["light_transmittance"] = s.transmittanceMap ? "map" : "traced";
  if (s.transmittanceMap) st.extra["transmittance_map_resolution"] = s.mapResolution;
}

}  // namespace scatterlab
