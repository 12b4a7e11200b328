#pragma once
/// The fast march's fused volume (issue 14): density and source radiance interleaved per voxel
/// as (D, S.r, S.g, S.b), so one trilinear lookup gives both with the weights and corner
/// addresses computed once. Stored as float (16 bytes per voxel) or, with
/// render.half_float_volumes, as IEEE half (8 bytes per voxel; Imath's conversions, each
/// channel divided by a per-volume scale so that its largest magnitude maps to 1024, far below
/// half's maximum of 65504). The march kernels (cpu/fused_march.h) read it through the plain
/// FusedVolumeView, because they are compiled for different instruction sets.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "core/grid.h"

namespace scatterlab {

/// What a march kernel reads: plain data only.
struct FusedVolumeView {
  const float* f32 = nullptr;                 ///< 4 floats per voxel, or
  const std::uint16_t* f16 = nullptr;         ///< 4 halves per voxel (value = half · scale)
  float scale[4] = {1.0f, 1.0f, 1.0f, 1.0f};  ///< per channel (half storage only)
  float maxIndex[3] = {0.0f, 0.0f, 0.0f};     ///< clamp of index coordinates (dims − 1)
  int maxBase[3] = {0, 0, 0};                 ///< trilinear base corner clamp (dims − 2)
  std::ptrdiff_t row = 0, slice = 0;          ///< voxel strides of y and z (x: 1 voxel)
};

class FusedVolume {
 public:
  FusedVolume() = default;
  /// Interleaves `d` and `r` (compatible() must hold); `half`: IEEE half storage.
  FusedVolume(const DensityGrid& d, const RadianceGrid& r, bool half) { build(d, r, half); }
  /// The same, into the storage this volume already holds where it has the size: a march that
  /// keeps its volume from frame to frame writes the same pages again instead of mapping and
  /// faulting in new ones (16 bytes a voxel: 32 MiB at 128³).
  void build(const DensityGrid& d, const RadianceGrid& r, bool half);
  /// Same bounds and dimensions, and at least two voxels along every axis (the kernels read a
  /// cell's two x neighbours as one contiguous load).
  static bool compatible(const DensityGrid& d, const RadianceGrid& r);

  const FusedVolumeView& view() const { return view_; }
  bool half() const { return view_.f16 != nullptr; }
  std::size_t bytes() const { return size_ * (f32_ ? sizeof(float) : sizeof(std::uint16_t)); }

  /// (D, S.r, S.g, S.b) at index coordinates u, clamped as Grid3::sampleIndex (portable code,
  /// for the march with the analytic light factor).
  void sample(Vec3 u, float out[4]) const;

 private:
  // Not value-initialised (build() writes every element, in parallel): zeroing them first was
  // a single-threaded pass whose page faults took most of a fresh render's march (per-voxel on
  // population/wisp_0, 128³, 160 × 120: 134 ms against 73 ms without it; the steps ~8 ms).
  std::unique_ptr<float[]> f32_;
  std::unique_ptr<std::uint16_t[]> f16_;
  std::size_t size_ = 0;  ///< elements of the one that is held (the other is null)
  FusedVolumeView view_;
};

}  // namespace scatterlab
