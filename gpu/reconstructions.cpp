#include "gpu/reconstructions.h"

#include <vector>

#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/device_samples.h"
#include "gpu/dispatch.h"
#include "gpu/empty_space.h"
#include "gpu/records.h"
#include "gpu/screen_pass.h"
#include "gpu/shaders.h"
#include "gpu/sphere_bins.h"
#include "gpu/tracing.h"
#include "shading/transport.h"

namespace scatterlab::gpu {

// ---------------------------------------------------------------- gradient splatting

Volume GradientSplatGpu::reconstruct(const Volume& density, std::span<const RadianceSample> samples,
                                     const Box& bounds, IVec3 dims, ReconstructionStats* stats,
                                     StageTimer* timer, DeviceSamples* resident,
                                     Buffer* uncoveredCount) {
  context();
  const bool occlusion = occlusion_ && sigmaT_ > 0.0f;
  const bool gather = pipeline_ == GpuPipeline::Compute;
  ProgramVariant splatVariant;
  if (gather) {
    splatVariant.compute = {"radiance_gather.comp.glsl"};
  } else {
    splatVariant.vertex = {"radiance_splat.vert.glsl"};
    splatVariant.fragment = {"radiance_splat.frag.glsl"};
  }
  const bool lampBounds = gather && bounds_ && lampScene_;
  const bool lit = gather && litScene_ && !LitReach(litScene_->lights).everywhere();
  if (occlusion || lampBounds || lit) {
    // The occlusion weights march the density, the lamps' bound reads it and the lights, the
    // cones' reach the lights, with common.glsl's lookups.
    auto& files = gather ? splatVariant.compute : splatVariant.fragment;
    files.insert(files.begin(), "common.glsl");
  }
  splatVariant.define("SL_OCCLUSION", occlusion)
      .define("SL_BOUNDED", bool(bounds_))
      .define("SL_LAMP_BOUNDS", lampBounds)
      .define("SL_LIT_REACH", lit)
      .define("SL_LOG_SPACE", lampBounds && log_);
  const Program& splat = program(splatVariant, gather ? "radiance gather" : "radiance splat");
  // The raster splat draws one instance per packed sample; the gather reads the samples as the
  // tracer left them (resident: this render's S and ∇S on the GPU, no upload) or uploads them.
  Buffer packedSamples;
  DeviceSamples uploaded;
  DeviceSamples* gathered = nullptr;
  if (!gather) {
    std::vector<GpuSplatSample> packed;
    packed.reserve(samples.size());
    for (const RadianceSample& s : samples)
      packed.push_back({{s.position, s.radius}, packRadiance(s)});
    packedSamples =
        Buffer(packed.size() * sizeof(GpuSplatSample), packed.data(), 0, "radiance samples");
  } else if (resident && resident->radianceCurrent &&
             (resident->onDevice || resident->size() == samples.size())) {
    gathered = resident;
  } else {
    DeviceSamples& d = resident ? *resident : uploaded;
    d.setPoints(samples);
    std::vector<GpuRadianceRecord> records;
    records.reserve(samples.size());
    for (const RadianceSample& s : samples) records.push_back(packRadiance(s));
    if (!records.empty())
      glNamedBufferSubData(d.radiance.id(), 0,
                           GLsizeiptr(records.size() * sizeof(GpuRadianceRecord)), records.data());
    gathered = &d;
  }
  const GLuint zeroCount = 0;
  Buffer counter(sizeof(GLuint), &zeroCount, 0, "uncovered voxel count");
  // Every voxel written: by the gather's imageStore, or (raster) after splatSlices clears each
  // layer; the normalize pass stores every voxel of `out`.
  const Texture sums = Texture::make3D(GL_RGBA32F, dims.x, dims.y, dims.z, "radiance splat sums",
                                       Texture::Contents::Overwritten);
  Volume out = makeRadianceVolume(bounds, dims, "source radiance (gradient splat)",
                                  Texture::Contents::Overwritten);
  const Vec3 cell = bounds.extent() / Vec3(dims);
  // The compute gather fills uncovered occupied voxels from the nearest sample, as the CPU;
  // a resident list's count is read on the GPU. Samples kept from frame to frame (a host list
  // the frame keeps) keep the voxels and their nearest samples too: found once, then written
  // from the list by a small pass (gpu::NearestFill).
  const bool countOnDevice = gather && gathered->onDevice.has_value();
  NearestFill* fill = nullptr;
  bool record = false;
  if (gather && resident && gathered == resident && !countOnDevice)
    fill = &resident->fillFor(bounds, dims, &record);
  enum class FillMode { Search, Record, Kept, Pass };
  const auto normalizeVariant = [&](FillMode m) {
    return ProgramVariant{.compute = {"common.glsl", "radiance_normalize.comp.glsl"}}
        .define("SL_LOG_SPACE", log_)
        .define("SL_NEAREST_FILL", gather)
        .define("SL_COUNT_ON_DEVICE", countOnDevice)
        .define("SL_FILL_RECORD", m == FillMode::Record)
        .define("SL_FILL_KEPT", m == FillMode::Kept)
        .define("SL_FILL_PASS", m == FillMode::Pass);
  };
  const Program& normalize = program(normalizeVariant(!fill    ? FillMode::Search
                                                      : record ? FillMode::Record
                                                               : FillMode::Kept),
                                     "radiance normalize");
  if (record) {
    // The programs of the frames that keep the list, made now: a steady frame creates no GL
    // object (programs are kept by their defines).
    (void)program(normalizeVariant(FillMode::Kept), "radiance normalize");
    (void)program(normalizeVariant(FillMode::Pass), "radiance nearest fill");
  }
  const BinBuffers* bins = nullptr;
  IVec3 binDims{0};
  if (gather) bins = &gathered->binsFor(bounds, dims, &binDims, "radiance gather");
  // The lights for the lamps' bound or the cones' reach, made before the gather is in use (with a
  // lamp inside the box they run the lamp model's pass).
  std::optional<TracingInputs> lights;
  if (lampBounds || lit)
    lights.emplace(lampBounds ? *lampScene_ : *litScene_, density, 0.0f, nullptr, timer);
  {
    std::optional<ScopedGpuTimer> t;  // the compute gather times its own dispatch
    if (!gather) t.emplace(timer, "radiance splat");
    splat.use();
    if (gather) {
      gathered->points.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
      gathered->radiance.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRadiance);
    } else {
      packedSamples.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSplatSamples);
    }
    if (bounds_) glUniform2f(splat.uniform("uTaylorBounds"), bounds_->lo, bounds_->hi);
    if (lights) lights->apply(splat);
    if (lit) glUniform1f(splat.uniform("uReach"), glm::length(cell));
    if (occlusion) {
      glBindTextureUnit(binding::kDensityTexture, density.texture.id());
      setVec3(splat, "uDensityScale", density.indexScale());
      setVec3(splat, "uDensityOffset", density.indexOffset());
      setIVec3(splat, "uDensityDims", density.dims);
      glUniform1f(splat.uniform("uSigmaT"), sigmaT_);
      const Vec3 dc = density.cellSize();
      glUniform1f(splat.uniform("uDensityVoxel"), std::min(dc.x, std::min(dc.y, dc.z)));
    }
    if (gather) {
      bins->bind();
      glBindImageTexture(binding::kSumsImage, sums.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
      setVec3(splat, "uGridMin", bounds.min);
      setVec3(splat, "uGridCell", cell);
      setIVec3(splat, "uGridDims", dims);
      setIVec3(splat, "uBins", binDims);
      glUniform1i(splat.uniform("uBinVoxels"), kBinVoxels);
      dispatch("radiance gather", {groups(dims.x, 4), groups(dims.y, 4), groups(dims.z, 4)}, timer);
    } else {
      splatSlices(splat, sums, bounds, dims, GLsizei(samples.size()), "radiance splat");
      checkGl("radiance splat");
    }
  }
  {
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    normalize.use();
    glBindImageTexture(binding::kSumsImage, sums.id(), 0, GL_TRUE, 0, GL_READ_ONLY, GL_RGBA32F);
    glBindImageTexture(binding::kRadianceImage, out.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY,
                       GL_RGBA32F);
    glBindTextureUnit(binding::kDensityTexture, density.texture.id());
    counter.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kCounters);
    setIVec3(normalize, "uGridDims", dims);
    setVec3(normalize, "uGridMin", bounds.min);
    setVec3(normalize, "uGridCell", cell);
    setVec3(normalize, "uDensityScale", density.indexScale());
    setVec3(normalize, "uDensityOffset", density.indexOffset());
    setIVec3(normalize, "uDensityDims", density.dims);
    glUniform1i(normalize.uniform("uSameGrid"), sameGrid(density, bounds, dims));
    if (gather) {
      gathered->points.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
      gathered->radiance.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRadiance);
      if (countOnDevice)
        gathered->onDevice->count.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
      else
        glUniform1ui(normalize.uniform("uSampleCount"), GLuint(gathered->size()));
    }
    if (fill) {
      fill->entries.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kFillEntries);
      fill->words.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kFillWords);
      glUniform1ui(normalize.uniform("uFillCapacity"), GLuint(fill->capacity));
    }
    out.densityInAlpha = sameGrid(density, bounds, dims);
    dispatch("radiance normalize", {groups(dims.x, 4), groups(dims.y, 4), groups(dims.z, 4)},
             timer);
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
  }
  if (fill && !record) {
    // The kept voxels from the kept list: at most 1024 workgroups, striding over the entries
    // the GPU counted (no read-back).
    const Program& pass = program(normalizeVariant(FillMode::Pass), "radiance nearest fill");
    pass.use();
    glBindImageTexture(binding::kRadianceImage, out.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY,
                       GL_RGBA32F);
    glBindTextureUnit(binding::kDensityTexture, density.texture.id());
    gathered->radiance.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRadiance);
    fill->entries.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kFillEntries);
    fill->words.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kFillWords);
    counter.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kCounters);
    glUniform1ui(pass.uniform("uFillCapacity"), GLuint(fill->capacity));
    setIVec3(pass, "uGridDims", dims);
    glUniform1i(pass.uniform("uSameGrid"), sameGrid(density, bounds, dims));
    dispatch("radiance nearest fill", {std::min<GLuint>(groups(fill->capacity, 64), 1024u), 1, 1},
             timer);
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
  }
  if (uncoveredCount) {
    *uncoveredCount = std::move(counter);
  } else if (stats) {
    GLuint n = 0;
    counter.read(&n, sizeof n);
    stats->uncovered = n;
  }
  return out;
}

// ---------------------------------------------------------------- per-voxel

Volume PerVoxelGpu::build(const Scene& scene, const Volume& density, const Box& bounds, IVec3 dims,
                          ReconstructionStats* stats, StageTimer* timer, const ShadowMaps* shadows,
                          Buffer* countersOut) {
  context();
  ProgramVariant variant{.compute = {"common.glsl", "per_voxel.comp.glsl"}};
  // The lights over as many dispatches as a driver's loop cap asks (1 on a GPU without one): a
  // voxel traces each light's shadow ray (with factored lights twice: factoredPart's and, for
  // the cones-ignored sums, factoredFreePart's).
  const int parts = lightDispatches(int(scene.lights.size()), 1.0,
                                    (factored_ ? 2.0 : 1.0) * diagonalSteps(scene, delta1_));
  variant.define("SL_FACTOR_LIGHTS", factored_)
      .define("SL_LAMP_MODEL", factored_ && lampModel_)
      .define("SL_LIT_REACH", factored_)
      .define("SL_LIGHT_PARTS", parts > 1);
  addShadowRaySkip(variant);
  const Program& program = gpu::program(addShadowVariant(shadows, variant), "per-voxel S");
  Volume out = makeRadianceVolume(bounds, dims, "source radiance (per voxel)",
                                  Texture::Contents::Overwritten);  // one store per voxel
  const GpuPerVoxelCounters zeros;
  Buffer counters(sizeof zeros, &zeros, 0, "per-voxel counters");
  TracingInputs inputs(scene, density, delta1_, shadows, timer);
  inputs.skipEmptySpace(timer);
  {
    program.use();
    inputs.apply(program);
    glBindImageTexture(binding::kRadianceImage, out.texture.id(), 0, GL_TRUE, 0,
                       parts > 1 && !factored_ ? GL_READ_WRITE : GL_WRITE_ONLY, GL_RGBA32F);
    counters.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kCounters);
    setIVec3(program, "uRadDims", dims);
    glUniform1i(program.uniform("uSameGrid"), sameGrid(density, bounds, dims));
    out.densityInAlpha = sameGrid(density, bounds, dims);
    setVec3(program, "uRadMin", bounds.min);
    const Vec3 cell = bounds.extent() / Vec3(dims);
    setVec3(program, "uRadCell", cell);
    if (factored_) glUniform1f(program.uniform("uReach"), glm::length(cell));
    const UVec3 size(groups(dims.x, 4), groups(dims.y, 4), groups(dims.z, 4));
    if (parts == 1) {
      dispatch("per-voxel S", size, timer);
    } else {
      // Factored: the parts' sums per voxel (each part stores every occupied voxel's), V made of
      // them by a last dispatch.
      std::vector<Texture> sums;
      if (factored_)
        for (GLuint k = 0; k < 4; ++k) {
          sums.push_back(Texture::make3D(GL_RGBA32F, dims.x, dims.y, dims.z, "per-voxel part sums",
                                         Texture::Contents::Overwritten));
          glBindImageTexture(binding::kPartSumsImage0 + k, sums.back().id(), 0, GL_TRUE, 0,
                             GL_READ_WRITE, GL_RGBA32F);
        }
      if (factored_) glUniform1i(program.uniform("uCombine"), 0);
      dispatchLightParts(program, parts, "per-voxel S", size,
                         GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT, timer);
      if (factored_) {
        glUniform1i(program.uniform("uCombine"), 1);
        dispatch("per-voxel S", size, timer);
      }
    }
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
  }
  if (countersOut) {
    *countersOut = std::move(counters);
  } else if (stats) {
    GpuPerVoxelCounters n;
    counters.read(&n, sizeof n);
    stats->traced = n.traced;
    stats->skipped = n.skipped;
  }
  return out;
}

}  // namespace scatterlab::gpu
