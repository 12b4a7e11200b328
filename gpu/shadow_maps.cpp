#include "gpu/shadow_maps.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/dispatch.h"
#include "gpu/shaders.h"
#include "shading/shadow_projection.h"

namespace scatterlab::gpu {

ProgramVariant& addShadowVariant(const ShadowMaps* shadows, ProgramVariant& v) {
  if (!shadows) return v;
  v.prepend("shadow.glsl");
  return v.define("SL_OBJECTS");
}

ShadowMaps::ShadowMaps(const Scene& scene, const ObjectGeometry& geometry,
                       const ShadowMapSettings& settings, StageTimer* timer)
    : settings_(settings) {
  if (!scene.objects) throw Error("ShadowMaps: the scene has no objects");
  const int res = settings.resolution;
  // The projections the CPU maps use too (shading/shadow_projection.h).
  const ShadowProjections proj = shadowProjections(scene, res);
  std::vector<GpuShadowLight> records;
  for (const ShadowLightMaps& l : proj.lights) {
    GpuShadowLight rec;
    rec.firstLayer = l.firstLayer;
    rec.kind = l.kind;
    rec.origin = l.origin;
    rec.texel = l.texel;
    rec.direction = l.direction;
    records.push_back(rec);
  }
  const std::vector<ShadowLayer>& layers = proj.layers;
  layers_ = int(layers.size());
  try {
    maps_ = Texture::make2DArray(GL_RG32F, res, res, std::max(layers_, 1), "shadow maps");
  } catch (const GpuError& e) {
    // The keys behind the size (issue 37: the error named only the texture).
    throw GpuError("'render.shadow_map.resolution' = " + std::to_string(res) + " with " +
                   std::to_string(layers_) + " shadow-map layer" + (layers_ == 1 ? "" : "s") +
                   " (one per directional or spot light, six per point light): " + e.what() +
                   "; use a lower resolution or fewer lights");
  }
  lights_ = Buffer(records.size() * sizeof(GpuShadowLight), records.data(), 0, "shadow lights");
  std::vector<glm::mat4> matrices;
  for (const ShadowLayer& l : layers) matrices.push_back(l.viewProj);
  matrices_ = Buffer(matrices.size() * sizeof(glm::mat4), matrices.data(), 0, "shadow matrices");
  if (layers.empty()) return;

  // Both programs are built before the timer starts (compiling is not the maps' cost).
  const Program& draw = program(
      {.vertex = {"objects.vert.glsl"}, .fragment = {"shadow_map.frag.glsl"}}, "shadow map");
  const Program& blur = program({.compute = {"shadow_blur.comp.glsl"}}, "shadow blur");
  ScopedGpuTimer t(timer, "shadow maps");
  const Texture depth = Texture::make2D(GL_DEPTH_COMPONENT32F, res, res, "shadow map depth");
  const Framebuffer fbo("shadow map");
  glNamedFramebufferTexture(fbo.id(), GL_DEPTH_ATTACHMENT, depth.id(), 0);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo.id());
  glViewport(0, 0, res, res);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glDisable(GL_SCISSOR_TEST);
  draw.use();
  for (int i = 0; i < layers_; ++i) {
    const ShadowLayer& l = layers[size_t(i)];
    glNamedFramebufferTextureLayer(fbo.id(), GL_COLOR_ATTACHMENT0, maps_.id(), 0, i);
    if (i == 0 &&
        glCheckNamedFramebufferStatus(fbo.id(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw GpuError("shadow maps: an RG32F layer is not a complete framebuffer");
    const float clear[4] = {l.far, l.far * l.far, 0.0f, 0.0f};
    glClearBufferfv(GL_COLOR, 0, clear);
    const float one = 1.0f;
    glClearBufferfv(GL_DEPTH, 0, &one);
    glUniformMatrix4fv(draw.uniform("uViewProj"), 1, GL_FALSE, glm::value_ptr(l.viewProj));
    setVec3(draw, "uShadowOrigin", l.origin);
    setVec3(draw, "uShadowDirection", l.direction);
    glUniform1i(draw.uniform("uShadowOrtho"), l.ortho ? 1 : 0);
    geometry.draw();
  }
  glDisable(GL_DEPTH_TEST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  checkGl("shadow maps");
  if (settings.type != ShadowMapSettings::Type::Vsm || settings.filter <= 1) return;
  // VSM: blur the moments (separable box filter), x into a scratch array, y back.
  const Texture scratch = Texture::make2DArray(GL_RG32F, res, res, layers_, "shadow blur scratch");
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
  blur.use();
  glUniform1i(blur.uniform("uRadius"), settings.filter / 2);
  glUniform1i(blur.uniform("uResolution"), res);
  for (int axis = 0; axis < 2; ++axis) {
    const Texture& src = axis == 0 ? maps_ : scratch;
    const Texture& dst = axis == 0 ? scratch : maps_;
    glBindImageTexture(binding::kBlurSource, src.id(), 0, GL_TRUE, 0, GL_READ_ONLY, GL_RG32F);
    glBindImageTexture(binding::kBlurTarget, dst.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RG32F);
    glUniform1i(blur.uniform("uAxis"), axis);
    dispatch("shadow map blur", {groups(size_t(res), 8), groups(size_t(res), 8), GLuint(layers_)});
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
  }
  checkGl("shadow map blur");
}

void ShadowMaps::bind(const Program& p) const {
  glBindTextureUnit(binding::kShadowTexture, maps_.id());
  lights_.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kShadowLights);
  matrices_.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kShadowMatrices);
  glUniform1i(p.uniform("uShadowMode"), settings_.type == ShadowMapSettings::Type::Vsm ? 0 : 1);
  glUniform1f(p.uniform("uShadowBias"), settings_.bias);
  glUniform1i(p.uniform("uShadowFilter"), settings_.filter);
  glUniform1f(p.uniform("uShadowBleed"), settings_.bleedReduction);
  glUniform1f(p.uniform("uShadowResolution"), float(settings_.resolution));
}

std::vector<float> ShadowMaps::readLayer(int layer) const {
  const int res = settings_.resolution;
  std::vector<float> out(size_t(res) * res * 2);
  countHostWait("shadow map read-back");
  glGetTextureSubImage(maps_.id(), 0, 0, 0, layer, res, res, 1, GL_RG, GL_FLOAT,
                       GLsizei(out.size() * sizeof(float)), out.data());
  checkGl("shadow map read-back");
  return out;
}

}  // namespace scatterlab::gpu
