#include "gpu/stages.h"

#include <vector>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/records.h"
#include "gpu/shaders.h"

namespace scatterlab::gpu {

TracingInputs::TracingInputs(const Scene& scene, const Volume& density, float delta1)
    : scene_(scene), density_(density), delta1_(delta1) {
  std::vector<GpuLight> packed;
  packed.reserve(scene.lights.size());
  for (const Light& l : scene.lights) packed.push_back(packLight(l));
  lights_ = Buffer(packed.size() * sizeof(GpuLight), packed.data(), 0, "lights");
}

void TracingInputs::apply(const Program& p) const {
  const Medium& m = scene_.medium;
  lights_.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLights);
  glBindTextureUnit(binding::kDensityTexture, density_.texture.id());
  glUniform1i(p.uniform("uLightCount"), GLint(scene_.lights.size()));
  glUniform1i(p.uniform("uPhaseType"), m.phase.type == Phase::Type::Isotropic ? 0 : 1);
  glUniform1f(p.uniform("uPhaseG"), m.phase.g);
  glUniform1f(p.uniform("uSigmaT"), m.sigmaT);
  glUniform1f(p.uniform("uDelta1"), delta1_);
  setVec3(p, "uBoxMin", density_.bounds.min);
  setVec3(p, "uBoxMax", density_.bounds.max);
  setVec3(p, "uDensityScale", density_.indexScale());
  setVec3(p, "uDensityOffset", density_.indexOffset());
  setIVec3(p, "uDensityDims", density_.dims);
  setVec3(p, "uEye", scene_.camera.position);
}

// ---------------------------------------------------------------- radiance evaluator

void VolumeTracerGpu::evaluate(const Scene& scene, const DensityGrid& density,
                               std::span<RadianceSample> samples, bool gradients) {
  const Volume d = uploadDensity(density);
  evaluate(scene, d, samples, gradients, nullptr);
}

void VolumeTracerGpu::evaluate(const Scene& scene, const Volume& density,
                               std::span<RadianceSample> samples, bool gradients,
                               StageTimer* timer) {
  context();
  if (samples.empty()) return;
  std::string key = gradients ? "volume tracer (S, grad S)" : "volume tracer (S)";
  if (factor_) key += log_ ? " ln V" : " V";
  const Program& program = cachedProgram(key, [&] {
    std::vector<std::string> defines;
    if (gradients) defines.push_back("SL_GRADIENTS");
    if (factor_) defines.push_back("SL_FACTOR_LIGHTS");
    if (log_) defines.push_back("SL_LOG_SPACE");
    return computeProgram({"common.glsl", "volume_tracer.comp.glsl"}, defines, key);
  });
  std::vector<GpuSamplePoint> pos;
  pos.reserve(samples.size());
  for (const RadianceSample& s : samples) pos.push_back({s.position});
  const Buffer positions(pos.size() * sizeof(GpuSamplePoint), pos.data(), 0, "sample positions");
  const Buffer results(samples.size() * sizeof(GpuRadianceRecord), nullptr, 0,
                       "sample S and grad S");
  const TracingInputs inputs(scene, density, delta1_);
  {
    ScopedGpuTimer t(timer, "radiance evaluation");
    program.use();
    inputs.apply(program);
    glUniform1ui(program.uniform("uCount"), GLuint(samples.size()));
    glUniform1f(program.uniform("uDelta2"), delta2_);
    positions.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
    results.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRadiance);
    glDispatchCompute(groups(samples.size(), 64), 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  }
  checkGl("radiance evaluation");
  std::vector<GpuRadianceRecord> r(samples.size());
  results.read(r.data(), r.size() * sizeof(GpuRadianceRecord));
  // Without SL_GRADIENTS the shader writes ∇S = 0, so the records unpack as they are.
  for (size_t i = 0; i < samples.size(); ++i) unpackRadiance(r[i], samples[i]);
}

// ---------------------------------------------------------------- gradient splatting

ReconstructionStats GradientSplatGpu::reconstruct(const Scene& scene, const DensityGrid& density,
                                                  std::span<const RadianceSample> samples,
                                                  RadianceGrid& out) {
  const Volume d = uploadDensity(density);
  ReconstructionStats st;
  const Volume v = reconstruct(d, samples, out.bounds(), out.dims(), &st, nullptr);
  out = readRadiance(v);
  return st;
}

Volume GradientSplatGpu::reconstruct(const Volume& density, std::span<const RadianceSample> samples,
                                     const Box& bounds, IVec3 dims, ReconstructionStats* stats,
                                     StageTimer* timer) {
  context();
  const bool occlusion = occlusion_ && sigmaT_ > 0.0f;
  std::string splatKey = occlusion ? "radiance splat (occlusion)" : "radiance splat";
  std::vector<std::string> splatDefines;
  if (occlusion) splatDefines.push_back("SL_OCCLUSION");
  if (bounds_) {
    splatDefines.push_back("SL_BOUNDED");
    splatKey += " bounded";
  }
  const Program& splat = cachedProgram(splatKey, [&] {
    if (!occlusion)
      return graphicsProgram({"radiance_splat.vert.glsl"}, {"radiance_splat.frag.glsl"},
                             splatDefines, splatKey);
    return graphicsProgram({"radiance_splat.vert.glsl"},
                           {"common.glsl", "radiance_splat.frag.glsl"}, splatDefines, splatKey);
  });
  const std::string normKey = log_ ? "radiance normalize (exp)" : "radiance normalize";
  const Program& normalize = cachedProgram(normKey, [&] {
    return computeProgram(
        {"radiance_normalize.comp.glsl"},
        log_ ? std::vector<std::string>{"SL_LOG_SPACE"} : std::vector<std::string>{}, normKey);
  });
  std::vector<GpuSplatSample> packed;
  packed.reserve(samples.size());
  for (const RadianceSample& s : samples)
    packed.push_back({{s.position, s.radius}, packRadiance(s)});
  const Buffer sampleBuf(packed.size() * sizeof(GpuSplatSample), packed.data(), 0,
                         "radiance samples");
  const GLuint zeroCount = 0;
  const Buffer counter(sizeof(GLuint), &zeroCount, 0, "uncovered voxel count");
  const Texture sums = Texture::make3D(GL_RGBA32F, dims.x, dims.y, dims.z, "radiance splat sums");
  Volume out = makeRadianceVolume(bounds, dims, "source radiance (gradient splat)");
  const Vec3 cell = bounds.extent() / Vec3(dims);
  {
    ScopedGpuTimer t(timer, "radiance splat");
    splat.use();
    sampleBuf.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSplatSamples);
    if (bounds_) glUniform2f(splat.uniform("uTaylorBounds"), bounds_->lo, bounds_->hi);
    if (occlusion) {
      glBindTextureUnit(binding::kDensityTexture, density.texture.id());
      setVec3(splat, "uDensityScale", density.indexScale());
      setVec3(splat, "uDensityOffset", density.indexOffset());
      setIVec3(splat, "uDensityDims", density.dims);
      glUniform1f(splat.uniform("uSigmaT"), sigmaT_);
      const Vec3 dc = density.cellSize();
      glUniform1f(splat.uniform("uDensityVoxel"), std::min(dc.x, std::min(dc.y, dc.z)));
    }
    splatSlices(splat, sums, bounds, dims, GLsizei(samples.size()), "radiance splat");
  }
  checkGl("radiance splat");
  {
    ScopedGpuTimer t(timer, "radiance normalize");
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    normalize.use();
    glBindImageTexture(binding::kSumsImage, sums.id(), 0, GL_TRUE, 0, GL_READ_ONLY, GL_RGBA32F);
    glBindImageTexture(binding::kRadianceImage, out.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY,
                       GL_RGBA32F);
    glBindTextureUnit(binding::kDensityTexture, density.texture.id());
    counter.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kCounters);
    setIVec3(normalize, "uGridDims", dims);
    // radiance voxel index v -> density texture coordinate (u + 0.5) / dims_density.
    const Vec3 dd = Vec3(density.dims), ds = density.indexScale(), dof = density.indexOffset();
    setVec3(normalize, "uDensityLookupScale", cell * ds / dd);
    setVec3(normalize, "uDensityLookupOffset", ((bounds.min + 0.5f * cell) * ds + dof + 0.5f) / dd);
    glUniform1i(normalize.uniform("uSameGrid"), density.dims == dims &&
                                                    density.bounds.min == bounds.min &&
                                                    density.bounds.max == bounds.max);
    glDispatchCompute(groups(dims.x, 4), groups(dims.y, 4), groups(dims.z, 4));
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
  }
  checkGl("radiance normalize");
  if (stats) {
    GLuint n = 0;
    counter.read(&n, sizeof n);
    stats->uncovered = n;
  }
  return out;
}

// ---------------------------------------------------------------- per-voxel

ReconstructionStats PerVoxelGpu::reconstruct(const Scene& scene, const DensityGrid& density,
                                             std::span<const RadianceSample>, RadianceGrid& out) {
  const Volume d = uploadDensity(density);
  const Volume v = build(scene, d, out.bounds(), out.dims(), nullptr, nullptr);
  out = readRadiance(v);
  return {};
}

Volume PerVoxelGpu::build(const Scene& scene, const Volume& density, const Box& bounds, IVec3 dims,
                          ReconstructionStats* stats, StageTimer* timer) {
  context();
  const Program& program = cachedProgram("per-voxel S", [] {
    return computeProgram({"common.glsl", "per_voxel.comp.glsl"}, {}, "per-voxel S");
  });
  Volume out = makeRadianceVolume(bounds, dims, "source radiance (per voxel)");
  const GpuPerVoxelCounters zeros;
  const Buffer counters(sizeof zeros, &zeros, 0, "per-voxel counters");
  const TracingInputs inputs(scene, density, delta1_);
  {
    ScopedGpuTimer t(timer, "per-voxel S");
    program.use();
    inputs.apply(program);
    glBindImageTexture(binding::kRadianceImage, out.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY,
                       GL_RGBA32F);
    counters.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kCounters);
    setIVec3(program, "uRadDims", dims);
    setVec3(program, "uRadMin", bounds.min);
    setVec3(program, "uRadCell", bounds.extent() / Vec3(dims));
    glDispatchCompute(groups(dims.x, 4), groups(dims.y, 4), groups(dims.z, 4));
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
  }
  checkGl("per-voxel S");
  if (stats) {
    GpuPerVoxelCounters n;
    counters.read(&n, sizeof n);
    stats->traced = n.traced;
    stats->skipped = n.skipped;
  }
  return out;
}

// ---------------------------------------------------------------- slice marcher

Image SliceMarcher::integrate(const Scene& scene, const DensityGrid& density,
                              const RadianceGrid& radiance) {
  const Volume d = uploadDensity(density);
  const Volume r = uploadRadiance(radiance);
  return integrate(scene, d, r, nullptr);
}

Image SliceMarcher::integrate(const Scene& scene, const Volume& density, const Volume& radiance,
                              StageTimer* timer, int* sliceCount) {
  context();
  std::string key = raySteps_ ? "slice marcher (ray steps)" : "slice marcher";
  if (factor_) key += " x A";
  const Program& program = cachedProgram(key, [&] {
    std::vector<std::string> defines;
    if (raySteps_) defines.push_back("SL_RAY_STEPS");
    if (factor_) defines.push_back("SL_FACTOR_LIGHTS");
    return graphicsProgram({"fullscreen.vert.glsl"}, {"common.glsl", "slice_march.frag.glsl"},
                           defines, key);
  });
  const Camera& cam = scene.camera;
  const auto gen = cam.rayGenerator();
  const Medium& m = scene.medium;
  const int w = cam.width, h = cam.height;
  const Texture target = Texture::make2D(GL_RGBA32F, w, h, "slice marcher image");
  const Framebuffer fbo("slice marcher target");
  glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT0, target.id(), 0);
  if (glCheckNamedFramebufferStatus(fbo.id(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw GpuError("slice marcher: RGBA32F image is not a complete framebuffer");
  const VertexArray vao("attribute-less");
  const TracingInputs inputs(scene, density, 0.0f);

  // View-depth range of the box (distance along the forward axis from the eye).
  const Box& b = density.bounds;
  float zmin = kInfinity, zmax = -kInfinity;
  for (int c = 0; c < 8; ++c) {
    const Vec3 p((c & 1) ? b.max.x : b.min.x, (c & 2) ? b.max.y : b.min.y,
                 (c & 4) ? b.max.z : b.min.z);
    const float z = glm::dot(p - gen.origin, gen.forward);
    zmin = std::min(zmin, z);
    zmax = std::max(zmax, z);
  }
  zmin = std::max(zmin, 0.0f);
  const int n = zmax > zmin && m.sigmaT > 0.0f
                    ? std::max(1, int(std::ceil((zmax - zmin) / settings_.step)))
                    : 0;
  const float dz = n > 0 ? (zmax - zmin) / float(n) : 0.0f;
  // Ray-step layers: enough for the longest chord through the box.
  const int layers = m.sigmaT > 0.0f
                         ? std::max(1, int(std::ceil(glm::length(b.extent()) / settings_.step)) + 1)
                         : 0;
  if (sliceCount) *sliceCount = raySteps_ ? layers : n;
  {
    ScopedGpuTimer t(timer, "slice march");
    glBindFramebuffer(GL_FRAMEBUFFER, fbo.id());
    glViewport(0, 0, w, h);
    const float clear[4] = {scene.background.x, scene.background.y, scene.background.z, 1.0f};
    glClearBufferfv(GL_COLOR, 0, clear);
    program.use();
    inputs.apply(program);
    glBindTextureUnit(binding::kRadianceTexture, radiance.texture.id());
    setVec3(program, "uRadScale", radiance.indexScale());
    setVec3(program, "uRadOffset", radiance.indexOffset());
    setIVec3(program, "uRadDims", radiance.dims);
    setVec3(program, "uForward", gen.forward);
    setVec3(program, "uRight", gen.right);
    setVec3(program, "uUp", gen.up);
    glUniform2f(program.uniform("uTanHalf"), gen.sx, gen.sy);
    glUniform2f(program.uniform("uSize"), float(w), float(h));
    glUniform1f(program.uniform("uAlbedo"), m.albedo);
    const GLint nearLoc = program.uniform("uDepthNear"), farLoc = program.uniform("uDepthFar");
    glBindVertexArray(vao.id());
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_SCISSOR_TEST);
    glEnable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    // rgb: dst = src + a·dst (paper Sec. 6); alpha: dst = a·dst keeps the transmittance.
    glBlendFuncSeparate(GL_ONE, GL_SRC_ALPHA, GL_ZERO, GL_SRC_ALPHA);
    if (raySteps_) {
      glUniform1f(program.uniform("uStep"), settings_.step);
      const GLint layerLoc = program.uniform("uLayer");
      for (int k = 0; k < layers; ++k) {
        glUniform1i(layerLoc, k);
        glDrawArrays(GL_TRIANGLES, 0, 3);
      }
    } else {
      for (int k = n - 1; k >= 0; --k) {
        glUniform1f(nearLoc, zmin + float(k) * dz);
        glUniform1f(farLoc, k == n - 1 ? zmax : zmin + float(k + 1) * dz);
        glDrawArrays(GL_TRIANGLES, 0, 3);
      }
    }
    glDisable(GL_BLEND);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  checkGl("slice march");
  std::vector<float> rgba(size_t(w) * h * 4);
  glGetTextureImage(target.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)),
                    rgba.data());
  checkGl("slice march read-back");
  Image img(w, h);
  img.alpha().resize(size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float* p = &rgba[(size_t(y) * w + x) * 4];
      img.at(x, y) = Vec3(p[0], p[1], p[2]);
      // The alpha channel blends as ZERO, SRC_ALPHA from a clear of 1: the view ray's
      // transmittance, the product of the slabs'.
      img.alpha()[size_t(y) * w + x] = 1.0f - p[3];
    }
  return img;
}

}  // namespace scatterlab::gpu
