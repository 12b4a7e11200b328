#include "gpu/stages.h"

#include <glm/gtc/type_ptr.hpp>
#include <vector>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/records.h"
#include "gpu/screen_pass.h"
#include "gpu/shaders.h"
#include "gpu/sphere_bins.h"
#include "shading/transport.h"

namespace scatterlab::gpu {

TracingInputs::TracingInputs(const Scene& scene, const Volume& density, float delta1,
                             const ShadowMaps* shadows)
    : scene_(scene), density_(density), delta1_(delta1), shadows_(shadows) {
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
  if (shadows_) shadows_->bind(p);
}

const ShadowMaps* SceneShadows::build(const Scene& scene, const ShadowMapSettings& settings,
                                      StageTimer* timer) {
  if (!scene.objects) return nullptr;
  context();
  if (!geometry) geometry = std::make_unique<ObjectGeometry>(*scene.objects);
  if (!maps) maps = std::make_unique<ShadowMaps>(scene, *geometry, settings, timer);
  return maps.get();
}

// ---------------------------------------------------------------- radiance evaluator

void VolumeTracerGpu::evaluate(const Scene& scene, const DensityGrid& density,
                               std::span<RadianceSample> samples, bool gradients) {
  const Volume d = uploadDensity(density);
  SceneShadows objects;
  evaluate(scene, d, samples, gradients, nullptr, objects.build(scene, shadowMap_, nullptr));
}

void VolumeTracerGpu::evaluate(const Scene& scene, const Volume& density,
                               std::span<RadianceSample> samples, bool gradients, StageTimer* timer,
                               const ShadowMaps* shadows) {
  context();
  if (samples.empty()) return;
  std::string key = gradients ? "volume tracer (S, grad S)" : "volume tracer (S)";
  if (factor_) key += log_ ? " ln V" : " V";
  if (lamp_) key += " lamp";
  std::vector<std::string> defines, files = {"common.glsl", "volume_tracer.comp.glsl"};
  if (gradients) defines.push_back("SL_GRADIENTS");
  if (factor_) defines.push_back("SL_FACTOR_LIGHTS");
  if (lamp_) defines.push_back("SL_LAMP_MODEL");
  if (log_) defines.push_back("SL_LOG_SPACE");
  addShadowVariant(shadows, key, files, defines);
  const Program& program = cachedProgram(key, [&] { return computeProgram(files, defines, key); });
  std::vector<GpuSamplePoint> pos;
  pos.reserve(samples.size());
  for (const RadianceSample& s : samples) pos.push_back({s.position});
  const Buffer positions(pos.size() * sizeof(GpuSamplePoint), pos.data(), 0, "sample positions");
  const Buffer results(samples.size() * sizeof(GpuRadianceRecord), nullptr, 0,
                       "sample S and grad S");
  const TracingInputs inputs(scene, density, delta1_, shadows);
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
  if (settingsBounds_ && lamp_) bounds_ = lampBounds(*settingsBounds_, scene, density);
  const Volume v = reconstruct(d, samples, out.bounds(), out.dims(), &st, nullptr);
  out = readRadiance(v);
  return st;
}

Volume GradientSplatGpu::reconstruct(const Volume& density, std::span<const RadianceSample> samples,
                                     const Box& bounds, IVec3 dims, ReconstructionStats* stats,
                                     StageTimer* timer) {
  context();
  const bool occlusion = occlusion_ && sigmaT_ > 0.0f;
  const bool gather = pipeline_ == GpuPipeline::Compute;
  std::string splatKey = gather ? "radiance gather" : "radiance splat";
  if (occlusion) splatKey += " (occlusion)";
  std::vector<std::string> splatDefines;
  if (occlusion) splatDefines.push_back("SL_OCCLUSION");
  if (bounds_) {
    splatDefines.push_back("SL_BOUNDED");
    splatKey += " bounded";
  }
  const Program& splat = cachedProgram(splatKey, [&] {
    if (gather)
      return computeProgram(
          occlusion ? std::vector<std::string>{"common.glsl", "radiance_gather.comp.glsl"}
                    : std::vector<std::string>{"radiance_gather.comp.glsl"},
          splatDefines, splatKey);
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
  std::optional<BinBuffers> bins;
  IVec3 binDims{0};
  if (gather) {
    std::vector<glm::vec4> spheres;
    spheres.reserve(samples.size());
    for (const RadianceSample& s : samples) spheres.emplace_back(s.position, s.radius);
    const SphereBins b = binSpheres(spheres, bounds, dims, "radiance gather");
    binDims = b.bins;
    bins.emplace(b);
  }
  {
    ScopedGpuTimer t(timer, gather ? "radiance gather" : "radiance splat");
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
    if (gather) {
      bins->bind();
      glBindImageTexture(binding::kSumsImage, sums.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
      setVec3(splat, "uGridMin", bounds.min);
      setVec3(splat, "uGridCell", cell);
      setIVec3(splat, "uGridDims", dims);
      setIVec3(splat, "uBins", binDims);
      glUniform1i(splat.uniform("uBinVoxels"), kBinVoxels);
      glDispatchCompute(groups(dims.x, 4), groups(dims.y, 4), groups(dims.z, 4));
    } else {
      splatSlices(splat, sums, bounds, dims, GLsizei(samples.size()), "radiance splat");
    }
  }
  checkGl(gather ? "radiance gather" : "radiance splat");
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
    glUniform1i(normalize.uniform("uSameGrid"), sameGrid(density, bounds, dims));
    out.densityInAlpha = sameGrid(density, bounds, dims);
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
  SceneShadows objects;
  const Volume v = build(scene, d, out.bounds(), out.dims(), nullptr, nullptr,
                         objects.build(scene, shadowMap_, nullptr));
  out = readRadiance(v);
  return {};
}

Volume PerVoxelGpu::build(const Scene& scene, const Volume& density, const Box& bounds, IVec3 dims,
                          ReconstructionStats* stats, StageTimer* timer,
                          const ShadowMaps* shadows) {
  context();
  std::string key = "per-voxel S";
  std::vector<std::string> defines, files = {"common.glsl", "per_voxel.comp.glsl"};
  addShadowVariant(shadows, key, files, defines);
  const Program& program = cachedProgram(key, [&] { return computeProgram(files, defines, key); });
  Volume out = makeRadianceVolume(bounds, dims, "source radiance (per voxel)");
  const GpuPerVoxelCounters zeros;
  const Buffer counters(sizeof zeros, &zeros, 0, "per-voxel counters");
  const TracingInputs inputs(scene, density, delta1_, shadows);
  {
    ScopedGpuTimer t(timer, "per-voxel S");
    program.use();
    inputs.apply(program);
    glBindImageTexture(binding::kRadianceImage, out.texture.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY,
                       GL_RGBA32F);
    counters.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kCounters);
    setIVec3(program, "uRadDims", dims);
    glUniform1i(program.uniform("uSameGrid"), sameGrid(density, bounds, dims));
    out.densityInAlpha = sameGrid(density, bounds, dims);
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
  SceneShadows objects;
  objects.build(scene, shadowMap_, nullptr);
  return integrate(scene, d, r, nullptr, nullptr, &objects);
}

namespace {

/// World -> clip of the camera, consistent with Camera::rayGenerator and the slice marcher's
/// pixel rays (GL row r = image row r, so clip y is flipped): x = q·right/sx, y = −q·up/sy,
/// w = q·forward (q = p − eye), and z maps view depth [nearD, farD] to [−1, 1].
glm::mat4 cameraViewProj(const Camera::RayGenerator& g, float nearD, float farD) {
  const float a = (farD + nearD) / (farD - nearD), b = -2.0f * farD * nearD / (farD - nearD);
  const auto row = [&](const Vec3& axis, float scale, float shift) {
    return glm::vec4(axis * scale, -glm::dot(axis, g.origin) * scale + shift);
  };
  const glm::mat4 rows(row(g.right, 1.0f / g.sx, 0.0f), row(g.up, -1.0f / g.sy, 0.0f),
                       row(g.forward, a, b), row(g.forward, 1.0f, 0.0f));
  return glm::transpose(rows);
}

/// NDC z of view depth z under cameraViewProj(nearD, farD).
float ndcDepth(float z, float nearD, float farD) {
  z = std::max(z, nearD);
  return (farD + nearD) / (farD - nearD) - 2.0f * farD * nearD / ((farD - nearD) * z);
}

}  // namespace

SurfacePass renderSurfaces(const Scene& scene, const SceneShadows& objects,
                           const TracingInputs& inputs, const Texture& color, StageTimer* timer) {
  const Camera& cam = scene.camera;
  const auto gen = cam.rayGenerator();
  const int w = cam.width, h = cam.height;
  const ShadowMaps* shadows = objects.maps.get();
  SurfacePass out;
  // The depth range: from the eye to the farthest corner of the medium box and the objects.
  out.farD = 0.0f;
  Box all = scene.medium.bounds;
  all.min = glm::min(all.min, scene.objects->bounds().min);
  all.max = glm::max(all.max, scene.objects->bounds().max);
  for (int c = 0; c < 8; ++c) {
    const Vec3 p((c & 1) ? all.max.x : all.min.x, (c & 2) ? all.max.y : all.min.y,
                 (c & 4) ? all.max.z : all.min.z);
    out.farD = std::max(out.farD, glm::dot(p - gen.origin, gen.forward));
  }
  out.farD = std::max(out.farD, 1e-6f) * 1.01f;
  out.nearD = out.farD * 1e-5f;
  out.depth = Texture::make2D(GL_DEPTH_COMPONENT32F, w, h, "surface depth");
  out.distance = Texture::make2D(GL_R32F, w, h, "surface distance");
  const Framebuffer surfaceFbo("surface pass");
  glNamedFramebufferTexture(surfaceFbo.id(), GL_COLOR_ATTACHMENT0, color.id(), 0);
  glNamedFramebufferTexture(surfaceFbo.id(), GL_COLOR_ATTACHMENT1, out.distance.id(), 0);
  glNamedFramebufferTexture(surfaceFbo.id(), GL_DEPTH_ATTACHMENT, out.depth.id(), 0);
  const GLenum both[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  glNamedFramebufferDrawBuffers(surfaceFbo.id(), 2, both);
  if (glCheckNamedFramebufferStatus(surfaceFbo.id(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw GpuError("surface pass: the framebuffer is not complete");
  std::vector<std::string> surfDefines, surfFiles = {"common.glsl", "surface.frag.glsl"};
  std::string k = "object surfaces";
  addShadowVariant(shadows, k, surfFiles, surfDefines);
  const Program& surf = cachedProgram(
      k, [&] { return graphicsProgram({"objects.vert.glsl"}, surfFiles, surfDefines, k); });
  ScopedGpuTimer t(timer, "surfaces");
  glBindFramebuffer(GL_FRAMEBUFFER, surfaceFbo.id());
  glViewport(0, 0, w, h);
  const float clear[4] = {scene.background.x, scene.background.y, scene.background.z, 1.0f};
  glClearBufferfv(GL_COLOR, 0, clear);
  const float none[4] = {3.0e38f, 0.0f, 0.0f, 0.0f};
  glClearBufferfv(GL_COLOR, 1, none);
  const float one = 1.0f;
  glClearBufferfv(GL_DEPTH, 0, &one);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glDisable(GL_SCISSOR_TEST);
  surf.use();
  inputs.apply(surf);
  glUniformMatrix4fv(surf.uniform("uViewProj"), 1, GL_FALSE,
                     glm::value_ptr(cameraViewProj(gen, out.nearD, out.farD)));
  glUniform1f(surf.uniform("uSurfaceOffset"), scene.objects->epsilon());
  objects.geometry->draw();
  glDisable(GL_DEPTH_TEST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  checkGl("object surfaces");
  return out;
}

void ScreenSurfaces::build(const Scene& scene, const SceneShadows& objects,
                           const TracingInputs& inputs, StageTimer* timer) {
  if (!objects.geometry || !objects.maps) return;
  radiance =
      Texture::make2D(GL_RGBA32F, scene.camera.width, scene.camera.height, "surface radiance");
  pass = renderSurfaces(scene, objects, inputs, radiance, timer);
  // The compute passes that read them come next.
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
  built = true;
}

void ScreenSurfaces::bind() const {
  if (!built) return;
  glBindTextureUnit(binding::kSurfaceTexture, pass.distance.id());
  glBindTextureUnit(binding::kSurfaceRadianceTexture, radiance.id());
}

namespace {

/// The slice marcher's program: ray-step layers or the paper's view-plane slabs, with the light
/// factor and the objects' shadow-map variant as asked.
const Program& sliceMarchProgram(bool raySteps, bool factor, bool lamp, const ShadowMaps* shadows) {
  std::string key = raySteps ? "slice marcher (ray steps)" : "slice marcher";
  if (factor) key += " x A";
  if (factor && lamp) key += " lamp";
  std::vector<std::string> defines, files = {"common.glsl", "slice_march.frag.glsl"};
  if (raySteps) defines.push_back("SL_RAY_STEPS");
  if (factor) defines.push_back("SL_FACTOR_LIGHTS");
  if (factor && lamp) defines.push_back("SL_LAMP_MODEL");
  addShadowVariant(shadows, key, files, defines);
  return cachedProgram(
      key, [&] { return graphicsProgram({"fullscreen.vert.glsl"}, files, defines, key); });
}

/// Where the slice marcher's layers lie.
struct SliceLayout {
  /// The paper's view-plane slabs: `slabs` of depth dz between the box's view depths zmin
  /// (from the eye on) and zmax.
  float zmin = 0.0f, zmax = 0.0f, dz = 0.0f;
  int slabs = 0;
  /// Ray-step layers: enough for the longest chord through the box.
  int layers = 0;
};

SliceLayout sliceLayout(const Camera::RayGenerator& gen, const Box& b, float sigmaT, float step) {
  SliceLayout l;
  const Camera::DepthRange z = Camera::viewDepthRange(gen, b);
  l.zmin = std::max(z.near, 0.0f);
  l.zmax = z.far;
  l.slabs =
      l.zmax > l.zmin && sigmaT > 0.0f ? std::max(1, int(std::ceil((l.zmax - l.zmin) / step))) : 0;
  l.dz = l.slabs > 0 ? (l.zmax - l.zmin) / float(l.slabs) : 0.0f;
  l.layers = sigmaT > 0.0f ? std::max(1, int(std::ceil(glm::length(b.extent()) / step)) + 1) : 0;
  return l;
}

/// Binds the march's inputs (density, lights, radiance volume) and sets the camera uniforms of
/// `p`, which is in use.
void setSliceMarchInputs(const Program& p, const Scene& scene, const TracingInputs& inputs,
                         const Volume& radiance) {
  const auto gen = scene.camera.rayGenerator();
  inputs.apply(p);
  glBindTextureUnit(binding::kRadianceTexture, radiance.texture.id());
  setVec3(p, "uRadScale", radiance.indexScale());
  setVec3(p, "uRadOffset", radiance.indexOffset());
  setIVec3(p, "uRadDims", radiance.dims);
  setVec3(p, "uForward", gen.forward);
  setVec3(p, "uRight", gen.right);
  setVec3(p, "uUp", gen.up);
  glUniform2f(p.uniform("uTanHalf"), gen.sx, gen.sy);
  glUniform2f(p.uniform("uSize"), float(scene.camera.width), float(scene.camera.height));
  glUniform1f(p.uniform("uAlbedo"), scene.medium.albedo);
}

/// Draws the layers of `l` far to near into the bound framebuffer with the paper's blending
/// (rgb: dst = src + a·dst, Sec. 6; alpha: dst = a·dst keeps the transmittance). `surface`:
/// the objects' surface pass, whose depth the layers behind it fail (view-plane slabs are
/// drawn at their near plane's depth; ray-step layers at the nearest, and clipped per pixel),
/// or null. Leaves blending and the depth test off.
void drawSliceLayers(const Program& p, const SliceLayout& l, bool raySteps, float step,
                     const SurfacePass* surface) {
  const GLint nearLoc = p.uniform("uDepthNear"), farLoc = p.uniform("uDepthFar");
  const GLint slabZLoc = p.uniform("uSlabNdcZ");
  if (surface) {
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_FALSE);
    glBindTextureUnit(binding::kSurfaceTexture, surface->distance.id());
    glUniform1f(slabZLoc, -1.0f);
  } else {
    glDisable(GL_DEPTH_TEST);
  }
  glDisable(GL_SCISSOR_TEST);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFuncSeparate(GL_ONE, GL_SRC_ALPHA, GL_ZERO, GL_SRC_ALPHA);
  if (raySteps) {
    glUniform1f(p.uniform("uStep"), step);
    const GLint layerLoc = p.uniform("uLayer");
    for (int k = 0; k < l.layers; ++k) {
      glUniform1i(layerLoc, k);
      glDrawArrays(GL_TRIANGLES, 0, 3);
    }
  } else {
    for (int k = l.slabs - 1; k >= 0; --k) {
      glUniform1f(nearLoc, l.zmin + float(k) * l.dz);
      glUniform1f(farLoc, k == l.slabs - 1 ? l.zmax : l.zmin + float(k + 1) * l.dz);
      if (surface)
        glUniform1f(slabZLoc, ndcDepth(l.zmin + float(k) * l.dz, surface->nearD, surface->farD));
      glDrawArrays(GL_TRIANGLES, 0, 3);
    }
  }
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_TRUE);
}

}  // namespace

Image SliceMarcher::integrate(const Scene& scene, const Volume& density, const Volume& radiance,
                              StageTimer* timer, int* sliceCount, const SceneShadows* objects) {
  context();
  const bool surfaces = objects && objects->geometry && objects->maps;
  const ShadowMaps* shadows = surfaces ? objects->maps.get() : nullptr;
  const Program& program = sliceMarchProgram(raySteps_, factor_, lamp_, shadows);
  const Camera& cam = scene.camera;
  const int w = cam.width, h = cam.height;
  const Texture target = Texture::make2D(GL_RGBA32F, w, h, "slice marcher image");
  const Framebuffer fbo("slice marcher target");
  glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT0, target.id(), 0);
  const VertexArray vao("attribute-less");
  const TracingInputs inputs(scene, density, surfaces ? delta1_ : 0.0f, shadows);
  const SliceLayout layout =
      sliceLayout(cam.rayGenerator(), density.bounds, scene.medium.sigmaT, settings_.step);
  if (sliceCount) *sliceCount = raySteps_ ? layout.layers : layout.slabs;

  // Scene objects: the surface pass fills the image with L_p (alpha 0: opaque), the depth
  // buffer and the view-ray distance of the first surface.
  SurfacePass surfacePass;
  if (surfaces) {
    surfacePass = renderSurfaces(scene, *objects, inputs, target, timer);
    glNamedFramebufferTexture(fbo.id(), GL_DEPTH_ATTACHMENT, surfacePass.depth.id(), 0);
  }
  if (glCheckNamedFramebufferStatus(fbo.id(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw GpuError("slice marcher: RGBA32F image is not a complete framebuffer");
  {
    ScopedGpuTimer t(timer, "slice march");
    glBindFramebuffer(GL_FRAMEBUFFER, fbo.id());
    glViewport(0, 0, w, h);
    const float clear[4] = {scene.background.x, scene.background.y, scene.background.z, 1.0f};
    if (!surfaces) glClearBufferfv(GL_COLOR, 0, clear);
    program.use();
    setSliceMarchInputs(program, scene, inputs, radiance);
    glBindVertexArray(vao.id());
    drawSliceLayers(program, layout, raySteps_, settings_.step, surfaces ? &surfacePass : nullptr);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  checkGl("slice march");
  // The alpha channel blends as ZERO, SRC_ALPHA from a clear of 1: the view ray's
  // transmittance, the product of the slabs'; 0 where a surface was drawn (alpha 1 as on the
  // CPU: the surface is opaque).
  return readScreenImage(target, w, h, OutputAlpha::Transmittance, "slice march read-back", timer);
}

}  // namespace scatterlab::gpu
