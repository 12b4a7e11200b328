#include "gpu/screen_pass.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/shaders.h"

namespace scatterlab::gpu {

ScreenPass::ScreenPass(const Scene& scene, const Volume& density, float delta1,
                       const ShadowMapSettings& shadowMap, StageTimer* timer)
    : scene_(scene),
      shadows_((context(), objects_.build(scene, shadowMap, timer))),
      inputs_(scene, density, delta1, shadows_, timer) {
  surfaces_.build(scene, objects_, inputs_, timer);
}

const Program& ScreenPass::program(std::string_view label, std::vector<std::string> files,
                                   std::vector<std::string> defines) const {
  ProgramVariant v{.compute = std::move(files), .defines = std::move(defines)};
  return gpu::program(addShadowVariant(shadows_, v), label);
}

void ScreenPass::bind(const Program& p) const {
  inputs_.apply(p);
  surfaces_.bind();
  setScreenCamera(p, scene_);
}

void setScreenCamera(const Program& p, const Scene& scene) {
  const auto gen = scene.camera.rayGenerator();
  setVec3(p, "uForward", gen.forward);
  setVec3(p, "uRight", gen.right);
  setVec3(p, "uUp", gen.up);
  glUniform2f(p.uniform("uTanHalf"), gen.sx, gen.sy);
  // The image size as the program declares it.
  if (p.declares("uImageSize"))
    glUniform2i(p.uniform("uImageSize"), scene.camera.width, scene.camera.height);
  if (p.declares("uSize"))
    glUniform2f(p.uniform("uSize"), float(scene.camera.width), float(scene.camera.height));
  glUniform1f(p.uniform("uAlbedo"), scene.medium.albedo);
}

void bindScreenImage(GLuint unit, const Texture& t, GLenum access) {
  glBindImageTexture(unit, t.id(), 0, GL_FALSE, 0, access, GL_RGBA32F);
}

Image readScreenImage(const Texture& t, int w, int h, OutputAlpha alpha, const char* pass,
                      StageTimer* timer) {
  const std::size_t n = std::size_t(w) * std::size_t(h);
  std::vector<float> rgba(n * 4);
  {
    ScopedGpuTimer time(timer, "read-back");
    const auto t0 = std::chrono::steady_clock::now();
    glGetTextureImage(t.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)),
                      rgba.data());
    countImageReadback(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  checkGl(pass);
  Image img(w, h);
  img.alpha().resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    img.pixels()[i] = Vec3(rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]);
    img.alpha()[i] = alpha == OutputAlpha::Alpha ? rgba[4 * i + 3] : 1.0f - rgba[4 * i + 3];
  }
  return img;
}

}  // namespace scatterlab::gpu
