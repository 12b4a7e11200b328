#pragma once
/// Binding points shared by the C++ passes and the shaders (DESIGN.md §8). compileShader
/// prepends "#define BINDING_<NAME> <value>" for every entry of kBindingDefines to each shader,
/// so GLSL writes `layout(binding = BINDING_LIGHTS)` and C++ binds at binding::kLights: each
/// number is written once, here. Needs no context.
///
/// GL keeps separate binding namespaces for storage buffers, texture units and image units.
/// A number is reused only by bindings that never meet in one program (e.g. the scan's and the
/// tracers' buffers); within one program every binding of a kind is distinct.

#include <epoxy/gl.h>

namespace scatterlab::gpu {

namespace binding {

// ---- shader storage buffers

/// GpuLight[] of the scene (common.glsl, every tracing pass).
inline constexpr GLuint kLights = 0;
/// GpuSamplePoint[]: the positions the volume tracer evaluates, and the current level's
/// samples in dynamic sampling.
inline constexpr GLuint kSamples = 1;
/// GpuBlob[] of density splatting.
inline constexpr GLuint kBlobs = 1;
/// GpuSplatSample[] of radiance splatting.
inline constexpr GLuint kSplatSamples = 1;
/// int32 level-0 ancestor of each sample of the current level (dynamic sampling).
inline constexpr GLuint kAncestors = 2;
/// float τ to the viewer of every level-0 sample (dynamic sampling).
inline constexpr GLuint kRootTau = 3;
/// uint counters a pass reports (GpuPerVoxelCounters; uncovered voxels of the normalisation;
/// the vertices A's far field computed).
inline constexpr GLuint kCounters = 3;
/// GpuRadianceRecord[]: S and ∇S per sample (volume tracer, dynamic sampling).
inline constexpr GLuint kRadiance = 4;
/// float E_j per sample (dynamic sampling).
inline constexpr GLuint kErrors = 5;
/// uint per level of dynamic sampling: the levels' sample counts, the overflow record and the
/// levels' indirect dispatch sizes (DynamicSamplingWorkspace, written on the GPU).
inline constexpr GLuint kLevelCounts = 6;
/// Grid information buffer of G_{k+1}: uint membership per vertex.
inline constexpr GLuint kInSet = 7;
/// Grid information buffer of G_{k+1}: int32 ancestor per vertex (INT_MAX = none).
inline constexpr GLuint kVertexAncestors = 8;
/// uint exclusive scan of kInSet: each member vertex's slot in the next level.
inline constexpr GLuint kOffsets = 9;
/// GpuSamplePoint[] of the next level (compaction output).
inline constexpr GLuint kNextSamples = 10;
/// int32 ancestors of the next level (compaction output).
inline constexpr GLuint kNextAncestors = 11;
/// float sums of mean_RGB|L̃ − L|·D per sample and group of kProbeGroup probes (dynamic sampling's
/// probe pass; never in one program with the grid information buffer).
inline constexpr GLuint kProbeSums = 7;
/// The radiance normalisation's kept nearest-sample fill (radiance_normalize.comp.glsl,
/// gpu::NearestFill): uvec2 (voxel, sample) entries, and two uints (the entries
/// written, whether they overflowed). Never in one program with kErrors or kInSet.
inline constexpr GLuint kFillEntries = 5;
inline constexpr GLuint kFillWords = 7;
/// Scan (scan.comp.glsl): input, output, per-block totals, and the scanned block totals.
inline constexpr GLuint kScanIn = 0;
inline constexpr GLuint kScanOut = 1;
inline constexpr GLuint kScanBlockSums = 2;
inline constexpr GLuint kScanScannedSums = 3;
/// The compute gathers' bins (gpu/sphere_bins.h): uint offset of each bin's list (bins + 1),
/// and the lists (sphere indices, ascending within a bin). Low numbers (GL guarantees only 8
/// storage-buffer bindings per compute shader); no pass that bins also uses ancestors or counters.
inline constexpr GLuint kBinOffsets = 2;
inline constexpr GLuint kBinItems = 3;
/// The passes that build the bins on the GPU (gpu::binSpheresGpu, sphere_bins.comp.glsl), with
/// the spheres at kSamples and the lists at kBinOffsets / kBinItems: the uint buffer holding the
/// sphere count (the caller's counts[], read at a slot), uint per bin (its list's length, counted
/// down again as the fill takes slots), and the overflow word (the entries needed, or 0).
inline constexpr GLuint kBinSphereCount = 4;
inline constexpr GLuint kBinCounts = 5;
inline constexpr GLuint kBinOverflow = 6;
/// uint bit masks of the lights a step in each brick of A's far field evaluates (far_mask.comp.glsl
/// writes them at kFarMaskOut, the compute view march reads them under SL_FAR_FIELD). Never in
/// one program with kVertexAncestors.
inline constexpr GLuint kFarMask = 8;
inline constexpr GLuint kFarMaskOut = 2;
/// GpuShadowLight[] per scene light (shadow.glsl, gpu/shadow_maps.h).
inline constexpr GLuint kShadowLights = 12;
/// mat4 world -> clip per shadow-map layer (shadow.glsl).
inline constexpr GLuint kShadowMatrices = 13;
/// GpuObjectVertex[]: the scene objects' triangles (objects.vert.glsl, gpu/objects.h).
inline constexpr GLuint kObjectVertices = 14;
/// int32 (key, code) pairs of a .sog residual hash (sog_residual.comp.glsl).
inline constexpr GLuint kResidualEntries = 0;
/// double error scale and absolute threshold of dynamic sampling (dynamic_level.comp.glsl).
inline constexpr GLuint kThreshold = 15;
/// uint trips and cut of the loop guard (gpu/shaders.h loopIterationLimit(); only where the
/// driver caps loop iterations), bound once for every program.
inline constexpr GLuint kLoopGuard = 16;
/// Dynamic sampling's budget (dynamic_budget.comp.glsl): per vertex of G_{k+1} 1 + the error
/// group of its worst marking candidate, and the group histograms of every split level.
inline constexpr GLuint kVertexKeys = 17;
inline constexpr GLuint kGroupHistograms = 18;
/// GpuRadianceRecord[] of the final sample list (dynamic sampling's assembly output).
inline constexpr GLuint kNextRadiance = 19;
/// uvec4 per part of dynamic sampling's final list (its first flag, its flags, its total's
/// counts slot, its group: dynamic_assemble.comp.glsl's SL_PART_ENDS; meets no kSamples there).
inline constexpr GLuint kAssembleParts = 1;
/// float[kBlueNoiseSize²] blue-noise table of `jittered-march` (shading/screen_march.h).
inline constexpr GLuint kJitterTable = 1;
/// float[slices + 1]: the view depths of `froxel`'s slice boundaries (FroxelSlicing::depth).
inline constexpr GLuint kFroxelDepths = 1;

// ---- texture units

/// The density volume (sampler3D uDensity).
inline constexpr GLuint kDensityTexture = 0;
/// The source-radiance volume the slice marcher reads (sampler3D uRadiance).
inline constexpr GLuint kRadianceTexture = 1;
/// The shadow maps: RG32F 2D array of moments (sampler2DArray uShadowMaps, shadow.glsl).
inline constexpr GLuint kShadowTexture = 2;
/// The slice marcher's surface distances: R32F view-ray distance of the first surface.
inline constexpr GLuint kSurfaceTexture = 3;
/// The surface pass's RGBA32F image of the per-pixel methods: L_p of the first surface (rgb).
inline constexpr GLuint kSurfaceRadianceTexture = 4;
/// The R32F lattice of a .sog residual F, read by texelFetch (sog_residual.comp.glsl).
inline constexpr GLuint kResidualTexture = 5;
/// The R32F empty-space grid: per block of voxels the largest density a lookup can read
/// (sampler3D uBlockMax, block_walk.glsl; gpu/empty_space.h).
inline constexpr GLuint kBlockMaxTexture = 6;
/// The RGBA32F grid of A's far field (render.far_field), a texel per vertex, read by texelFetch
/// in the compute view march (sampler3D uFarField, common.glsl farLookup). A 3D texture, not a
/// storage buffer: a 256³ medium's grid is 272 MB, above the 128 MiB that llvmpipe and Mesa's
/// Intel drivers address in one storage block (GL's minimum is 16 MiB).
inline constexpr GLuint kFarFieldTexture = 7;

// ---- image units

/// RGBA32F sums of radiance splatting, read by the normalisation.
inline constexpr GLuint kSumsImage = 0;
/// The R32F empty-space grid its build pass writes (block_max.comp.glsl).
inline constexpr GLuint kBlockMaxImage = 0;
/// The RGBA32F source-radiance volume a compute pass writes.
inline constexpr GLuint kRadianceImage = 1;
/// The shadow-map blur's source and target layers (shadow_blur.comp.glsl).
inline constexpr GLuint kBlurSource = 2;
inline constexpr GLuint kBlurTarget = 3;
/// RGBA32F 2D images of the screen-space passes of light-space-march and radial-blur: the one a
/// pass reads, the one it writes, and the base image (boundary term, alpha) it adds to.
inline constexpr GLuint kScreenInImage = 2;
inline constexpr GLuint kScreenOutImage = 3;
inline constexpr GLuint kScreenBaseImage = 4;
/// RGBA32F (L, T) of `jittered-march`'s low-resolution march.
inline constexpr GLuint kLowResImage = 2;
/// R32F depth where each low-resolution march ended (+∞: the ray missed the box).
inline constexpr GLuint kLowResDepthImage = 3;
/// RGBA32F full-resolution output of a per-pixel pass (rgb radiance, a transmittance).
inline constexpr GLuint kOutputImage = 4;
/// RGBA32F froxel volume of `froxel`: (L, T) after each froxel.
inline constexpr GLuint kFroxelImage = 5;
/// R32F per-light transmittance maps of `froxel`, stacked along z (light l at z / res = l).
inline constexpr GLuint kTransmittanceMapImage = 6;
/// R32F lattice of a .sog residual F (written by the scatter), and the R32F density volume it
/// is added to.
inline constexpr GLuint kResidualImage = 0;
inline constexpr GLuint kDensityImage = 1;
/// Per-voxel S split over dispatches with factored lights (per_voxel.comp.glsl SL_LIGHT_PARTS,
/// where the driver caps loops): RGBA32F sums per voxel over the parts' lights, (s, outside), a,
/// sf and af of FactoredSourceRadiance. That program binds no screen image.
inline constexpr GLuint kPartSumsImage0 = 2;
inline constexpr GLuint kPartSumsImage1 = 3;
inline constexpr GLuint kPartSumsImage2 = 4;
inline constexpr GLuint kPartSumsImage3 = 5;
/// The RGBA32F grid of A's far field as far_field.comp.glsl writes it (and, updating it in
/// place, reads it). That program binds no other image.
inline constexpr GLuint kFarFieldImage = 0;

}  // namespace binding

/// A binding as the shaders see it: "#define <name> <value>".
struct BindingDefine {
  const char* name;
  GLuint value;
};

/// Every binding above under its GLSL name; compileShader prepends all of them to every shader.
inline constexpr BindingDefine kBindingDefines[] = {
    {"BINDING_LIGHTS", binding::kLights},
    {"BINDING_SAMPLES", binding::kSamples},
    {"BINDING_BLOBS", binding::kBlobs},
    {"BINDING_SPLAT_SAMPLES", binding::kSplatSamples},
    {"BINDING_ANCESTORS", binding::kAncestors},
    {"BINDING_ROOT_TAU", binding::kRootTau},
    {"BINDING_COUNTERS", binding::kCounters},
    {"BINDING_RADIANCE", binding::kRadiance},
    {"BINDING_ERRORS", binding::kErrors},
    {"BINDING_FAR_MASK", binding::kFarMask},
    {"BINDING_FAR_MASK_OUT", binding::kFarMaskOut},
    {"BINDING_LEVEL_COUNTS", binding::kLevelCounts},
    {"BINDING_THRESHOLD", binding::kThreshold},
    {"BINDING_LOOP_GUARD", binding::kLoopGuard},
    {"BINDING_RESIDUAL_ENTRIES", binding::kResidualEntries},
    {"BINDING_IN_SET", binding::kInSet},
    {"BINDING_VERTEX_ANCESTORS", binding::kVertexAncestors},
    {"BINDING_OFFSETS", binding::kOffsets},
    {"BINDING_NEXT_SAMPLES", binding::kNextSamples},
    {"BINDING_VERTEX_KEYS", binding::kVertexKeys},
    {"BINDING_GROUP_HISTOGRAMS", binding::kGroupHistograms},
    {"BINDING_NEXT_RADIANCE", binding::kNextRadiance},
    {"BINDING_ASSEMBLE_PARTS", binding::kAssembleParts},
    {"BINDING_NEXT_ANCESTORS", binding::kNextAncestors},
    {"BINDING_PROBE_SUMS", binding::kProbeSums},
    {"BINDING_FILL_ENTRIES", binding::kFillEntries},
    {"BINDING_FILL_WORDS", binding::kFillWords},
    {"BINDING_SCAN_IN", binding::kScanIn},
    {"BINDING_SCAN_OUT", binding::kScanOut},
    {"BINDING_SCAN_BLOCK_SUMS", binding::kScanBlockSums},
    {"BINDING_SCAN_SCANNED_SUMS", binding::kScanScannedSums},
    {"BINDING_SHADOW_LIGHTS", binding::kShadowLights},
    {"BINDING_SHADOW_MATRICES", binding::kShadowMatrices},
    {"BINDING_OBJECT_VERTICES", binding::kObjectVertices},
    {"BINDING_DENSITY_TEXTURE", binding::kDensityTexture},
    {"BINDING_RADIANCE_TEXTURE", binding::kRadianceTexture},
    {"BINDING_BLOCK_MAX_TEXTURE", binding::kBlockMaxTexture},
    {"BINDING_BLOCK_MAX_IMAGE", binding::kBlockMaxImage},
    {"BINDING_FAR_FIELD_TEXTURE", binding::kFarFieldTexture},
    {"BINDING_FAR_FIELD_IMAGE", binding::kFarFieldImage},
    {"BINDING_PART_SUMS_IMAGE0", binding::kPartSumsImage0},
    {"BINDING_PART_SUMS_IMAGE1", binding::kPartSumsImage1},
    {"BINDING_PART_SUMS_IMAGE2", binding::kPartSumsImage2},
    {"BINDING_PART_SUMS_IMAGE3", binding::kPartSumsImage3},
    {"BINDING_SHADOW_TEXTURE", binding::kShadowTexture},
    {"BINDING_SURFACE_TEXTURE", binding::kSurfaceTexture},
    {"BINDING_SURFACE_RADIANCE_TEXTURE", binding::kSurfaceRadianceTexture},
    {"BINDING_RESIDUAL_TEXTURE", binding::kResidualTexture},
    {"BINDING_SUMS_IMAGE", binding::kSumsImage},
    {"BINDING_RADIANCE_IMAGE", binding::kRadianceImage},
    {"BINDING_BLUR_SOURCE", binding::kBlurSource},
    {"BINDING_BLUR_TARGET", binding::kBlurTarget},
    {"BINDING_SCREEN_IN_IMAGE", binding::kScreenInImage},
    {"BINDING_SCREEN_OUT_IMAGE", binding::kScreenOutImage},
    {"BINDING_SCREEN_BASE_IMAGE", binding::kScreenBaseImage},
    {"BINDING_JITTER_TABLE", binding::kJitterTable},
    {"BINDING_FROXEL_DEPTHS", binding::kFroxelDepths},
    {"BINDING_LOW_RES_IMAGE", binding::kLowResImage},
    {"BINDING_LOW_RES_DEPTH_IMAGE", binding::kLowResDepthImage},
    {"BINDING_OUTPUT_IMAGE", binding::kOutputImage},
    {"BINDING_BIN_OFFSETS", binding::kBinOffsets},
    {"BINDING_BIN_ITEMS", binding::kBinItems},
    {"BINDING_BIN_SPHERE_COUNT", binding::kBinSphereCount},
    {"BINDING_BIN_COUNTS", binding::kBinCounts},
    {"BINDING_BIN_OVERFLOW", binding::kBinOverflow},
    {"BINDING_FROXEL_IMAGE", binding::kFroxelImage},
    {"BINDING_TRANSMITTANCE_MAP_IMAGE", binding::kTransmittanceMapImage},
    {"BINDING_RESIDUAL_IMAGE", binding::kResidualImage},
    {"BINDING_DENSITY_IMAGE", binding::kDensityImage},
};

}  // namespace scatterlab::gpu
