#pragma once
/// Volumes on the GPU: 3D textures over the medium box with the cell-centre convention of
/// core/grid.h, their upload and read-back, and density construction by splatting (paper
/// Sec. 6). Everything here needs a current context (gpu::context()).

#include <memory>
#include <span>

#include "core/density_model.h"
#include "core/grid.h"
#include "core/scene.h"
#include "core/stages.h"
#include "gpu/gl.h"
#include "gpu/timer.h"

namespace scatterlab {
class SogDensity;
}

namespace scatterlab::gpu {

struct DeviceLights;

/// A 3D texture over `bounds`: voxel i's centre at bounds.min + (i + ½)·cell, GL_LINEAR with
/// CLAMP_TO_EDGE (so lookups match Grid3::sample inside the box). Density volumes are R32F,
/// radiance volumes RGBA32F (rgb = S; a = the density of the same grid where densityInAlpha).
struct Volume {
  Texture texture;
  Box bounds;
  IVec3 dims{0};
  /// A radiance volume on the density's grid whose alpha holds the density voxel by voxel
  /// (written by the reconstructions): the compute view march then reads D and S in one
  /// trilinear lookup of 8 texels per step instead of two of 8 (cpu/fused_volume.h's twin).
  bool densityInAlpha = false;
  /// A density volume's empty-space grid (gpu/empty_space.h), built by its first use: a new
  /// density is a new Volume, so the grid never outlives the voxels it was built from.
  mutable std::shared_ptr<const Texture> blockMax;
  /// A density volume's last lights on the device (gpu/tracing.h), with the lamp model's k_l
  /// looked up in this density: the passes of a frame share them, and a frame whose lights did
  /// not change uploads and looks up nothing.
  mutable std::shared_ptr<const DeviceLights> lights;

  Vec3 cellSize() const { return bounds.extent() / Vec3(dims); }
  Vec3 indexScale() const { return Vec3(1.0f) / cellSize(); }
  Vec3 indexOffset() const { return -bounds.min / cellSize() - 0.5f; }
};

/// Whether a volume over `bounds` with `dims` voxels is `v`'s grid.
inline bool sameGrid(const Volume& v, const Box& bounds, IVec3 dims) {
  return v.dims == dims && v.bounds.min == bounds.min && v.bounds.max == bounds.max;
}

Volume uploadDensity(const DensityGrid& grid);
Volume uploadRadiance(const RadianceGrid& grid);
/// Read back to host memory (waits for the GPU).
DensityGrid readDensity(const Volume& v);
RadianceGrid readRadiance(const Volume& v);
/// An RGBA32F radiance volume: zeros, or (Overwritten) undefined for a pass that writes every
/// voxel.
Volume makeRadianceVolume(const Box& bounds, IVec3 dims, std::string_view label,
                          Texture::Contents contents = Texture::Contents::Zeroed);

/// Density construction by splatting (paper Sec. 6; GPU twin of GaussianDensity::build): for
/// each z slice, one quad per blob bounding the blob's culling sphere (3r) cut by the slice,
/// blended additively (in blob order) into that layer of an R32F 3D texture.
/// Additive slice splatting, the mechanism shared by density construction (paper Sec. 6) and
/// radiance splatting (Sec. 4): for every Z layer of the 3D float texture `target` (`dims`
/// voxels over `bounds`) the layer is cleared, uniform uSliceZ is set to the layer centre's z,
/// and `instances` bounding quads (4-vertex triangle strips, attribute-less) are drawn with
/// GL_ONE/GL_ONE blending. Sets uGridMin, uGridCell, uGridDims; `program` must be bound with its
/// own uniforms and buffers. Needs the GL context; throws GpuError naming `pass` when a layer is
/// not a complete framebuffer.
void splatSlices(const Program& program, const Texture& target, const Box& bounds, IVec3 dims,
                 GLsizei instances, const char* pass);

/// The Gaussians' density w·exp(−|x − c|²/r²), culled at kGaussianCullRadius·r, summed at the
/// voxel centres in blob order (GaussianDensity::build's twin): GpuPipeline::Compute gathers
/// per voxel from the blobs binned on the host (density_gather.comp.glsl; GPU time "density
/// gather"), GpuPipeline::Raster splats slice by slice (the paper's; "density splat").
Volume splatGaussians(std::span<const GaussianBlob> blobs, const Box& bounds, IVec3 dims,
                      StageTimer* timer = nullptr, GpuPipeline pipeline = GpuPipeline::Compute);

/// The density of a .sog medium on the GPU (SogModel::splat's twin): the Gaussians splatted
/// (splatGaussians), then F added by a compute pass that samples the residual lattice as the CPU
/// does, d = max(0, D̃ + F). The lattice is uploaded sparsely (the hash's entries as a list,
/// scattered by a compute pass) and kept for the process while the same model object lives, so
/// a rebuild of the density from it (another resolution or box, a Renderer re-building the
/// density of a kept medium) uploads no residual; `residualUploaded` says whether this call
/// uploaded it. GPU times: "density splat", "residual upload", "residual add".
Volume splatSog(const std::shared_ptr<const SogDensity>& sog, const Box& bounds, IVec3 dims,
                StageTimer* timer = nullptr, bool* residualUploaded = nullptr,
                GpuPipeline pipeline = GpuPipeline::Compute);

/// The scene's density volume at medium.resolution: splatted on the GPU when the medium is a
/// sum of Gaussians or a .sog model (splatSog), else built on the CPU and uploaded (stage
/// "density upload"). `splatted` reports which.
Volume buildDensity(const Scene& scene, StageTimer* timer = nullptr, bool* splatted = nullptr,
                    GpuPipeline pipeline = GpuPipeline::Compute);

}  // namespace scatterlab::gpu
