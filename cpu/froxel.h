#pragma once
/// `froxel` on the CPU (docs/competitors.md; Wronski 2014, Hillaire 2015 — the volumetric fog
/// of Unreal, Frostbite and Godot). A camera-frustum-aligned grid of nx × ny × nz froxels: column
/// (i, j) is the ray through image point ((i + ½)·W/nx, (j + ½)·H/ny), slice k the view depths
/// [z_k, z_{k+1}] of FroxelSlicing (exponential by default). Two passes:
///  1. scatter + accumulate, per column, front to back: at each froxel's centre x (view depth
///     (z_k + z_{k+1})/2), with Δt the slice's length along the column's ray,
///       L += T·Ω·(1 − e^(−σt·D(x)·Δt))·S(x),  T *= e^(−σt·D(x)·Δt),
///     and (L, T) after slice k is stored in froxel (i, j, k); S traced to every light (step
///     delta1) or from per-light transmittance maps (TransmittanceMaps);
///  2. one lookup per pixel: trilinear in (column, depth) at the pixel's end depth — its first
///     surface, else `far` — where depth interpolates between slice boundaries (boundary 0 holds
///     L = 0, T = 1); the pixel is L + T·(surface radiance or background).

#include <vector>

#include "core/image.h"
#include "core/progress.h"
#include "core/scene.h"
#include "core/stages.h"
#include "shading/screen_march.h"

namespace scatterlab {

/// Per-light transmittance maps over the medium box (light_transmittance = map): voxel centre
/// x of light l holds V_l(x)·e^(−σt·τ(x → l)) (objects block; τ traced with step delta1), looked
/// up trilinearly. The source at x is then Σ_l E_l(x)·f(ω_l → ω)·map_l(x).
class TransmittanceMaps {
 public:
  TransmittanceMaps(const Scene& scene, const DensityGrid& density, int resolution, float delta1);
  Vec3 source(const Vec3& x, const Vec3& toViewer) const;
  const std::vector<DensityGrid>& maps() const { return maps_; }

 private:
  const Scene& scene_;
  std::vector<DensityGrid> maps_;
};

/// The accumulated volume: (L, T) after each froxel; i fastest, then j, then the slice k.
struct FroxelVolume {
  IVec3 dims{0};
  FroxelSlicing slicing;
  std::vector<Vec3> L;
  std::vector<float> T;
  size_t index(int i, int j, int k) const { return (size_t(k) * dims.y + j) * dims.x + i; }
};

/// Pass 1. `maps`: null to trace the transmittance.
FroxelVolume froxelAccumulate(const Scene& scene, const DensityGrid& density,
                              const FroxelSettings& s, float delta1, const TransmittanceMaps* maps);

/// Pass 2 for one ray of pixel (x, y) ending at ray distance `tEnd` (+∞: no surface):
/// trilinear (L, T).
void froxelLookup(const FroxelVolume& v, const Camera::RayGenerator& rays, int x, int y,
                  const Ray& ray, float tEnd, Vec3& L, float& T);

/// The whole method (pass 2 adds surfaces and background per pixel). `passMs` receives the
/// wall times of the passes (map, accumulate, lookup).
Image froxelRender(const Scene& scene, const DensityGrid& density, const FroxelSettings& s,
                   float delta1, float minTransmittance, Progress* progress, Json* passMs);

}  // namespace scatterlab
