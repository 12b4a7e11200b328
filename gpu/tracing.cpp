#include "gpu/tracing.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/gtc/type_ptr.hpp>
#include <vector>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/empty_space.h"
#include "gpu/records.h"
#include "gpu/shaders.h"

namespace scatterlab::gpu {

namespace {

/// The density texture and common.glsl's uniforms of its lookups (densityAtIndex, the box).
void bindDensityLookup(const Program& p, const Volume& density) {
  glBindTextureUnit(binding::kDensityTexture, density.texture.id());
  setVec3(p, "uBoxMin", density.bounds.min);
  setVec3(p, "uBoxMax", density.bounds.max);
  setVec3(p, "uDensityScale", density.indexScale());
  setVec3(p, "uDensityOffset", density.indexOffset());
  setIVec3(p, "uDensityDims", density.dims);
}

}  // namespace

std::shared_ptr<const DeviceLights> deviceLights(const Scene& scene, const Volume& density,
                                                 StageTimer* timer) {
  std::vector<GpuLight> packed;
  packed.reserve(scene.lights.size());
  for (const Light& l : scene.lights) packed.push_back(packLight(l));
  const float sigmaT = scene.medium.sigmaT;
  if (const auto& kept = density.lights;
      kept && kept->sigmaT == sigmaT && kept->packed.size() == packed.size() &&
      std::memcmp(kept->packed.data(), packed.data(), packed.size() * sizeof(GpuLight)) == 0)
    return kept;
  // Dropped first: where nothing else holds them, their buffer goes back to the recycler for the
  // new lights (a light moved from frame to frame makes no GL object). Where they had A's far
  // field (render.far_field), the new lights hold them until the view march has updated that
  // grid from them light by light.
  std::shared_ptr<const DeviceLights> before;
  if (const auto& kept = density.lights; kept && kept->farField.id() && kept->sigmaT == sigmaT &&
                                         kept->packed.size() == packed.size()) {
    kept->before.reset();
    before = kept;
  }
  density.lights.reset();
  auto lights = std::make_shared<DeviceLights>();
  lights->before = std::move(before);
  lights->buffer = Buffer(packed.size() * sizeof(GpuLight), packed.data(), 0, "lights");
  // The lamp model's k_l (lamp.x) and min_l m_l (lights[0].lamp.y), where a point or spot light
  // is inside the box: one small pass here, where every program that evaluates the model read
  // the density at each light per march step, sample and probe (and the gather at every voxel).
  const bool lampInside =
      std::any_of(scene.lights.begin(), scene.lights.end(), [&](const Light& l) {
        return l.type != Light::Type::Directional && density.bounds.contains(l.position);
      });
  if (lampInside) {
    const Program& p =
        program({.compute = {"common.glsl", "lamp_k.comp.glsl"}, .defines = {"SL_LAMP_MODEL"}},
                "lamp model");
    p.use();
    lights->buffer.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLights);
    bindDensityLookup(p, density);
    glUniform1i(p.uniform("uLightCount"), GLint(scene.lights.size()));
    glUniform1f(p.uniform("uSigmaT"), sigmaT);
    glUniform1f(p.uniform("uBoxDiagonal"), glm::length(density.bounds.extent()));
    dispatch("lamp model", {1, 1, 1}, timer);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
  lights->packed = std::move(packed);
  lights->sigmaT = sigmaT;
  density.lights = lights;
  return lights;
}

TracingInputs::TracingInputs(const Scene& scene, const Volume& density, float delta1,
                             const ShadowMaps* shadows, StageTimer* timer)
    : scene_(scene),
      density_(density),
      delta1_(delta1),
      shadows_(shadows),
      lights_(deviceLights(scene, density, timer)) {}

double diagonalSteps(const Scene& scene, float step) {
  return std::ceil(double(glm::length(scene.medium.bounds.extent())) / double(step)) + 1.0;
}

void TracingInputs::skipEmptySpace(StageTimer* timer) {
  blockMax_ = &blockMaxGrid(density_, timer);
}

void TracingInputs::apply(const Program& p) const {
  const Medium& m = scene_.medium;
  lights_->buffer.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLights);
  bindDensityLookup(p, density_);
  glUniform1i(p.uniform("uLightCount"), GLint(scene_.lights.size()));
  glUniform1i(p.uniform("uPhaseType"), m.phase.type == Phase::Type::Isotropic ? 0 : 1);
  glUniform1f(p.uniform("uPhaseG"), m.phase.g);
  glUniform1f(p.uniform("uSigmaT"), m.sigmaT);
  glUniform1f(p.uniform("uDelta1"), delta1_);
  setVec3(p, "uEye", scene_.camera.position);
  if (shadows_) shadows_->bind(p);
  if (p.declares("uBlocks")) {
    if (!blockMax_)
      throw GpuError("program '" + p.label() +
                     "' skips empty space in its shadow rays: TracingInputs::skipEmptySpace "
                     "was not called");
    glBindTextureUnit(binding::kBlockMaxTexture, blockMax_->id());
    setIVec3(p, "uBlocks", blockCount(density_));
  }
}

const ShadowMaps* SceneShadows::build(const Scene& scene, const ShadowMapSettings& settings,
                                      StageTimer* timer) {
  if (!scene.objects) return nullptr;
  context();
  if (!geometry) geometry = std::make_unique<ObjectGeometry>(*scene.objects);
  if (!maps) maps = std::make_unique<ShadowMaps>(scene, *geometry, settings, timer);
  return maps.get();
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
  ProgramVariant variant{.vertex = {"objects.vert.glsl"},
                         .fragment = {"common.glsl", "surface.frag.glsl"}};
  const Program& surf = program(addShadowVariant(shadows, variant), "object surfaces");
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

}  // namespace scatterlab::gpu
