#include "gpu/volume.h"

#include <memory>
#include <vector>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/records.h"
#include "gpu/shaders.h"
#include "gpu/sphere_bins.h"
#include "media/sog.h"

namespace scatterlab::gpu {

Volume uploadDensity(const DensityGrid& g) {
  context();
  Volume v;
  v.bounds = g.bounds();
  v.dims = g.dims();
  v.texture = Texture::make3D(GL_R32F, v.dims.x, v.dims.y, v.dims.z, "density volume",
                              Texture::Contents::Overwritten);  // the upload below
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTextureSubImage3D(v.texture.id(), 0, 0, 0, 0, v.dims.x, v.dims.y, v.dims.z, GL_RED, GL_FLOAT,
                      g.data().data());
  checkGl("density upload");
  return v;
}

Volume makeRadianceVolume(const Box& bounds, IVec3 dims, std::string_view label,
                          Texture::Contents contents) {
  context();
  Volume v;
  v.bounds = bounds;
  v.dims = dims;
  v.texture = Texture::make3D(GL_RGBA32F, dims.x, dims.y, dims.z, label, contents);
  return v;
}

Volume uploadRadiance(const RadianceGrid& g) {
  Volume v =
      makeRadianceVolume(g.bounds(), g.dims(), "radiance volume", Texture::Contents::Overwritten);
  // RGB32F would do, but RGBA32F is the image format the compute passes write.
  std::vector<float> rgba(g.size() * 4);
  for (size_t i = 0; i < g.size(); ++i) {
    rgba[4 * i] = g.data()[i].x;
    rgba[4 * i + 1] = g.data()[i].y;
    rgba[4 * i + 2] = g.data()[i].z;
    rgba[4 * i + 3] = 0.0f;
  }
  glTextureSubImage3D(v.texture.id(), 0, 0, 0, 0, v.dims.x, v.dims.y, v.dims.z, GL_RGBA, GL_FLOAT,
                      rgba.data());
  checkGl("radiance upload");
  return v;
}

DensityGrid readDensity(const Volume& v) {
  context();
  DensityGrid g(v.bounds, v.dims);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  countHostWait("density read-back");
  glGetTextureImage(v.texture.id(), 0, GL_RED, GL_FLOAT, GLsizei(g.size() * sizeof(float)),
                    g.data().data());
  checkGl("density read-back");
  return g;
}

RadianceGrid readRadiance(const Volume& v) {
  context();
  RadianceGrid g(v.bounds, v.dims);
  std::vector<float> rgba(g.size() * 4);
  countHostWait("radiance read-back");
  glGetTextureImage(v.texture.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)),
                    rgba.data());
  checkGl("radiance read-back");
  for (size_t i = 0; i < g.size(); ++i)
    g.data()[i] = Vec3(rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]);
  return g;
}

void splatSlices(const Program& program, const Texture& target, const Box& bounds, IVec3 dims,
                 GLsizei instances, const char* pass) {
  const Vec3 cell = bounds.extent() / Vec3(dims);
  setVec3(program, "uGridMin", bounds.min);
  setVec3(program, "uGridCell", cell);
  setIVec3(program, "uGridDims", dims);
  const GLint sliceLoc = program.uniform("uSliceZ");
  const Framebuffer fbo(std::string(pass) + " target");
  const VertexArray vao("attribute-less");
  glBindVertexArray(vao.id());
  glBindFramebuffer(GL_FRAMEBUFFER, fbo.id());
  glViewport(0, 0, dims.x, dims.y);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_SCISSOR_TEST);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_ONE);
  const float zero[4] = {0, 0, 0, 0};
  for (int k = 0; k < dims.z; ++k) {
    glNamedFramebufferTextureLayer(fbo.id(), GL_COLOR_ATTACHMENT0, target.id(), 0, k);
    if (k == 0 &&
        glCheckNamedFramebufferStatus(fbo.id(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw GpuError(std::string(pass) + ": 3D texture layer is not a complete framebuffer");
    glClearBufferfv(GL_COLOR, 0, zero);
    glUniform1f(sliceLoc, bounds.min.z + (float(k) + 0.5f) * cell.z);
    if (instances > 0) glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, instances);
  }
  glDisable(GL_BLEND);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

namespace {

/// splatGaussians under GpuPipeline::Compute.
Volume gatherGaussians(std::span<const GaussianBlob> blobs, const Box& bounds, IVec3 dims,
                       StageTimer* timer) {
  const Program& program =
      gpu::program({.compute = {"density_gather.comp.glsl"}}, "density gather");
  Volume v;
  v.bounds = bounds;
  v.dims = dims;
  // density_gather.comp stores every voxel.
  v.texture = Texture::make3D(GL_R32F, dims.x, dims.y, dims.z, "density volume (gathered)",
                              Texture::Contents::Overwritten);
  std::vector<GpuBlob> packed;
  std::vector<glm::vec4> spheres;
  packed.reserve(blobs.size());
  spheres.reserve(blobs.size());
  for (const GaussianBlob& b : blobs) {
    packed.push_back(packBlob(b));
    spheres.emplace_back(b.center, kGaussianCullRadius * b.radius);
  }
  const SphereBins bins = binSpheres(spheres, bounds, dims, "density gather");
  const BinBuffers binBufs(bins);
  const Buffer blobBuf(packed.size() * sizeof(GpuBlob), packed.data(), 0, "gaussian blobs");
  ScopedGpuTimer t(timer, "density gather");
  program.use();
  glUniform1f(program.uniform("uCull"), kGaussianCullRadius);
  setVec3(program, "uGridMin", bounds.min);
  setVec3(program, "uGridCell", bounds.extent() / Vec3(dims));
  setIVec3(program, "uGridDims", dims);
  setIVec3(program, "uBins", bins.bins);
  glUniform1i(program.uniform("uBinVoxels"), kBinVoxels);
  blobBuf.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBlobs);
  binBufs.bind();
  glBindImageTexture(binding::kDensityImage, v.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
  dispatch("density gather", {groups(dims.x, 4), groups(dims.y, 4), groups(dims.z, 4)});
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                  GL_TEXTURE_UPDATE_BARRIER_BIT);
  checkGl("density gather");
  return v;
}

}  // namespace

Volume splatGaussians(std::span<const GaussianBlob> blobs, const Box& bounds, IVec3 dims,
                      StageTimer* timer, GpuPipeline pipeline) {
  context();
  if (pipeline == GpuPipeline::Compute) return gatherGaussians(blobs, bounds, dims, timer);
  const Program& program =
      gpu::program({.vertex = {"density_splat.vert.glsl"}, .fragment = {"density_splat.frag.glsl"}},
                   "density splat");
  Volume v;
  v.bounds = bounds;
  v.dims = dims;
  // splatSlices clears each layer before it blends into it.
  v.texture = Texture::make3D(GL_R32F, dims.x, dims.y, dims.z, "density volume (splatted)",
                              Texture::Contents::Overwritten);
  std::vector<GpuBlob> packed;
  packed.reserve(blobs.size());
  for (const GaussianBlob& b : blobs) packed.push_back(packBlob(b));
  const Buffer blobBuf(packed.size() * sizeof(GpuBlob), packed.data(), 0, "gaussian blobs");
  ScopedGpuTimer t(timer, "density splat");
  program.use();
  glUniform1f(program.uniform("uCull"), kGaussianCullRadius);
  blobBuf.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kBlobs);
  splatSlices(program, v.texture, bounds, dims, GLsizei(blobs.size()), "density splat");
  checkGl("density splat");
  return v;
}

namespace {

/// The residual lattice of the last .sog model put on the GPU, and that model (held weakly: the
/// lattice is reused only while the very same model object lives, so a file rewritten and read
/// again is never confused with the old one). Kept for the process (never deleted, like the
/// cached programs: no GL call during static destruction).
struct ResidualLattice {
  std::weak_ptr<const SogDensity> model;
  const SogDensity* address = nullptr;
  Texture texture;
};

ResidualLattice& residualCache() {
  static ResidualLattice* cache = new ResidualLattice();
  return *cache;
}

/// F of `sog` as an R32F texture on its lattice: the hash's entries uploaded as a list and
/// scattered by a compute pass (sog_residual.comp.glsl, SL_SCATTER); reused while the model is
/// the same object. GPU time: "residual upload" (only when uploaded).
const Texture& residualLattice(const std::shared_ptr<const SogDensity>& sog, StageTimer* timer,
                               bool* uploaded) {
  ResidualLattice& cache = residualCache();
  *uploaded = false;
  if (cache.texture && cache.address == sog.get() && cache.model.lock() == sog)
    return cache.texture;
  const ResidualHash& r = sog->model().residual;
  const IVec3 n = r.dims();
  const std::vector<std::pair<std::uint32_t, std::int16_t>> entries = r.entries();
  std::vector<GLint> packed(2 * entries.size());
  for (std::size_t e = 0; e < entries.size(); ++e) {
    packed[2 * e] = GLint(entries[e].first);
    packed[2 * e + 1] = GLint(entries[e].second);
  }
  cache.model.reset();
  cache.address = nullptr;
  cache.texture = Texture::make3D(GL_R32F, n.x, n.y, n.z, "sog residual lattice");
  const Buffer list(packed.size() * sizeof(GLint), packed.data(), 0, "sog residual entries");
  const Program& scatter = program(
      {.compute = {"sog_residual.comp.glsl"}, .defines = {"SL_SCATTER"}}, "sog residual scatter");
  ScopedGpuTimer t(timer, "residual upload");
  const float zero = 0.0f;
  glClearTexImage(cache.texture.id(), 0, GL_RED, GL_FLOAT, &zero);
  if (!entries.empty()) {
    scatter.use();
    glUniform1ui(scatter.uniform("uCount"), GLuint(entries.size()));
    setIVec3(scatter, "uLatticeDims", n);
    glUniform1f(scatter.uniform("uStep"), r.step());
    list.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kResidualEntries);
    glBindImageTexture(binding::kResidualImage, cache.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY,
                       GL_R32F);
    dispatch("residual upload", linearDispatch(groups(entries.size(), 64)));
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
  }
  checkGl("sog residual upload");
  cache.model = sog;
  cache.address = sog.get();
  *uploaded = true;
  return cache.texture;
}

}  // namespace

Volume splatSog(const std::shared_ptr<const SogDensity>& sog, const Box& bounds, IVec3 dims,
                StageTimer* timer, bool* residualUploaded, GpuPipeline pipeline) {
  const SogModel& model = sog->model();
  Volume v = splatGaussians(model.gaussians, bounds, dims, timer, pipeline);
  bool uploaded = false;
  const bool useF = model.residual.size() > 0;
  const Texture* lattice = useF ? &residualLattice(sog, timer, &uploaded) : nullptr;
  if (residualUploaded) *residualUploaded = uploaded;
  const Program& add = program({.compute = {"sog_residual.comp.glsl"}}, "sog residual add");
  const ResidualHash& r = model.residual;
  ScopedGpuTimer t(timer, "residual add");
  add.use();
  setVec3(add, "uGridMin", bounds.min);
  setVec3(add, "uGridCell", bounds.extent() / Vec3(dims));
  setIVec3(add, "uGridDims", dims);
  setVec3(add, "uLatticeMin", r.bounds().min);
  setVec3(add, "uLatticeMax", r.bounds().max);
  setVec3(add, "uLatticeCell", r.bounds().extent() / Vec3(r.dims()));
  setIVec3(add, "uLatticeDims", r.dims());
  glUniform1i(add.uniform("uHasResidual"), useF ? 1 : 0);
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
  if (lattice) glBindTextureUnit(binding::kResidualTexture, lattice->id());
  glBindImageTexture(binding::kDensityImage, v.texture.id(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_R32F);
  dispatch("residual add", {groups(dims.x, 4), groups(dims.y, 4), groups(dims.z, 4)});
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                  GL_TEXTURE_UPDATE_BARRIER_BIT);
  checkGl("sog residual add");
  return v;
}

Volume buildDensity(const Scene& scene, StageTimer* timer, bool* splatted, GpuPipeline pipeline) {
  const Medium& m = scene.medium;
  if (m.density->isSumOfGaussians()) {
    if (splatted) *splatted = true;
    return splatGaussians(*m.density->gaussians(), m.bounds, m.resolution, timer, pipeline);
  }
  if (const auto sog = std::dynamic_pointer_cast<const SogDensity>(m.density)) {
    if (splatted) *splatted = true;
    return splatSog(sog, m.bounds, m.resolution, timer, nullptr, pipeline);
  }
  if (splatted) *splatted = false;
  DensityGrid grid(m.bounds, m.resolution);
  m.density->build(grid);
  ScopedGpuTimer t(timer, "density upload");
  return uploadDensity(grid);
}

}  // namespace scatterlab::gpu
