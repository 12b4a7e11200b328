#include "gpu/shadow_maps.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/dispatch.h"
#include "gpu/shaders.h"

namespace scatterlab::gpu {

namespace {

/// One map layer to render: world -> clip, and how its metric d is measured.
struct Layer {
  glm::mat4 viewProj{1.0f};
  Vec3 origin{0.0f}, direction{0.0f};
  bool ortho = false;
  float far = 1.0f;  ///< the clear value of d (no surface)
};

/// Spots wider than this get a cube (one perspective map cannot hold them well).
constexpr float kMaxSpotFovDeg = 120.0f;

std::array<Vec3, 8> corners(const Box& b) {
  std::array<Vec3, 8> c;
  for (int i = 0; i < 8; ++i)
    c[i] = Vec3(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z);
  return c;
}

/// An up vector not parallel to `dir`.
Vec3 upFor(const Vec3& dir) {
  return std::abs(dir.y) < 0.9f ? Vec3(0, 1, 0) : Vec3(1, 0, 0);
}

/// Near and far distances of a perspective map from `pos` covering `b`.
void nearFar(const Vec3& pos, const Box& b, float& nearD, float& farD) {
  farD = 0.0f;
  for (const Vec3& c : corners(b)) farD = std::max(farD, glm::length(c - pos));
  farD = farD * 1.01f + 1e-6f;
  nearD = std::max(farD * 1e-5f, 1e-7f);
}

void addCube(const Vec3& pos, const Box& b, int res, GpuShadowLight& rec,
             std::vector<Layer>& layers) {
  float n, f;
  nearFar(pos, b, n, f);
  rec.kind = 0;
  rec.origin = pos;
  rec.texel = 2.0f / float(res);  // 2·tan(45°)/res per unit distance
  const glm::mat4 proj = glm::perspective(glm::radians(90.0f), 1.0f, n, f);
  const Vec3 dirs[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const Vec3& d : dirs) {
    Layer l;
    l.viewProj =
        proj * glm::lookAt(pos, pos + d, std::abs(d.y) > 0.5f ? Vec3(0, 0, 1) : Vec3(0, 1, 0));
    l.origin = pos;
    l.far = f;
    layers.push_back(l);
  }
}

}  // namespace

void addShadowVariant(const ShadowMaps* shadows, std::string& key, std::vector<std::string>& files,
                      std::vector<std::string>& defines) {
  if (!shadows) return;
  key += " +objects";
  files.insert(files.begin(), "shadow.glsl");
  defines.push_back("SL_OBJECTS");
}

ShadowMaps::ShadowMaps(const Scene& scene, const ObjectGeometry& geometry,
                       const ShadowMapSettings& settings, StageTimer* timer)
    : settings_(settings) {
  if (!scene.objects) throw Error("ShadowMaps: the scene has no objects");
  const int res = settings.resolution;
  Box bounds = scene.medium.bounds;
  bounds.min = glm::min(bounds.min, scene.objects->bounds().min);
  bounds.max = glm::max(bounds.max, scene.objects->bounds().max);

  std::vector<GpuShadowLight> records;
  std::vector<Layer> layers;
  for (const Light& light : scene.lights) {
    GpuShadowLight rec;
    rec.firstLayer = int(layers.size());
    if (light.type == Light::Type::Point) {
      addCube(light.position, bounds, res, rec, layers);
    } else if (light.type == Light::Type::Spot) {
      const float half = std::acos(std::clamp(light.cosOuter, -1.0f, 1.0f));
      // A little wider than the cone, so that its edge is not at the map's edge.
      const float fov = std::min(2.0f * half * 1.05f + glm::radians(1.0f), glm::radians(179.0f));
      if (fov > glm::radians(kMaxSpotFovDeg)) {
        addCube(light.position, bounds, res, rec, layers);
      } else {
        float n, f;
        nearFar(light.position, bounds, n, f);
        rec.kind = 1;
        rec.origin = light.position;
        rec.texel = 2.0f * std::tan(0.5f * fov) / float(res);
        Layer l;
        const Vec3 d = glm::normalize(light.direction);
        l.viewProj = glm::perspective(fov, 1.0f, n, f) *
                     glm::lookAt(light.position, light.position + d, upFor(d));
        l.origin = light.position;
        l.far = f;
        layers.push_back(l);
      }
    } else {
      // Orthographic, fitted to the box in the light's view.
      const Vec3 d = glm::normalize(light.direction);
      const Vec3 centre = bounds.center();
      const float radius = 0.5f * glm::length(bounds.extent());
      const Vec3 eye = centre - d * (radius * 1.01f + 1e-6f);
      const glm::mat4 view = glm::lookAt(eye, centre, upFor(d));
      Vec3 lo(kInfinity), hi(-kInfinity);
      for (const Vec3& c : corners(bounds)) {
        const Vec3 v = Vec3(view * glm::vec4(c, 1.0f));
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
      }
      const float pad = 0.005f * std::max(hi.x - lo.x, hi.y - lo.y) + 1e-6f;
      lo -= Vec3(pad);
      hi += Vec3(pad);
      const float far = -lo.z * 1.01f + 1e-6f;  // view space looks down -z
      rec.kind = 2;
      rec.origin = eye;
      rec.direction = d;
      rec.texel = std::max(hi.x - lo.x, hi.y - lo.y) / float(res);
      Layer l;
      l.viewProj = glm::ortho(lo.x, hi.x, lo.y, hi.y, 0.0f, far) * view;
      l.origin = eye;
      l.direction = d;
      l.ortho = true;
      l.far = far;
      layers.push_back(l);
    }
    records.push_back(rec);
  }
  layers_ = int(layers.size());
  maps_ = Texture::make2DArray(GL_RG32F, res, res, std::max(layers_, 1), "shadow maps");
  lights_ = Buffer(records.size() * sizeof(GpuShadowLight), records.data(), 0, "shadow lights");
  std::vector<glm::mat4> matrices;
  for (const Layer& l : layers) matrices.push_back(l.viewProj);
  matrices_ = Buffer(matrices.size() * sizeof(glm::mat4), matrices.data(), 0, "shadow matrices");
  if (layers.empty()) return;

  // Both programs are built before the timer starts (compiling is not the maps' cost).
  const Program& draw = cachedProgram("shadow map", [] {
    return graphicsProgram({"objects.vert.glsl"}, {"shadow_map.frag.glsl"}, {}, "shadow map");
  });
  const Program& blur = cachedProgram(
      "shadow blur", [] { return computeProgram({"shadow_blur.comp.glsl"}, {}, "shadow blur"); });
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
    const Layer& l = layers[size_t(i)];
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
    glDispatchCompute(groups(size_t(res), 8), groups(size_t(res), 8), GLuint(layers_));
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
  glGetTextureSubImage(maps_.id(), 0, 0, 0, layer, res, res, 1, GL_RG, GL_FLOAT,
                       GLsizei(out.size() * sizeof(float)), out.data());
  checkGl("shadow map read-back");
  return out;
}

}  // namespace scatterlab::gpu
