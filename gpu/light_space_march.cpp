#include "gpu/light_space_march.h"

#include <vector>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/frame.h"
#include "gpu/screen_pass.h"
#include "gpu/shaders.h"
#include "gpu/tracing.h"

namespace scatterlab::gpu {

Image LightSpaceMarchGpu::integrate(Frame& frame, const Scene& scene, Progress*) {
  checkLightSpaceMarchScene(scene, s_);
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  // D̄ from the density read back once (the volume may have been splatted on the GPU).
  mean_ = s_.light == LightTransmittance::Mean ? meanDensity(f.hostDensity()) : 0.0f;
  return integrate(scene, f.density, mean_, &f.timer);
}

Image LightSpaceMarchGpu::integrate(const Scene& scene, const DensityGrid& density) {
  context();
  const Volume d = uploadDensity(density);
  return integrate(scene, d, meanDensity(density), nullptr);
}

Image LightSpaceMarchGpu::integrate(const Scene& scene, const Volume& density, float mean,
                                    StageTimer* timer) {
  checkLightSpaceMarchScene(scene, s_);
  const ScreenPass pass(scene, density, delta1_, shadowMap_, timer);
  shadowMaps_ = pass.shadows() ? int(scene.lights.size()) : 0;
  const bool traced = s_.light == LightTransmittance::Traced;
  const Program& march =
      pass.program(traced ? "light-space march (traced)" : "light-space march (mean)",
                   {"common.glsl", "light_space_march.comp.glsl"},
                   traced ? std::vector<std::string>{"SL_MARCH", "SL_TRACED"}
                          : std::vector<std::string>{"SL_MARCH"});
  const Program& sum = program(
      {.compute = {"common.glsl", "light_space_march.comp.glsl"}, .defines = {"SL_BLOCK_SUM"}},
      "light-space march block sum");
  const int w = scene.camera.width, h = scene.camera.height, M = s_.interleave;
  const Texture terms = Texture::make2D(GL_RGBA32F, w, h, "light-space march terms");
  const Texture base = Texture::make2D(GL_RGBA32F, w, h, "light-space march base");
  const Texture rows = Texture::make2D(GL_RGBA32F, w, h, "light-space march row sums");
  const Texture out = Texture::make2D(GL_RGBA32F, w, h, "light-space march image");
  {
    ScopedGpuTimer t(timer, "light-space march");
    march.use();
    pass.bind(march);
    glUniform1i(march.uniform("uInterleave"), M);
    glUniform1i(march.uniform("uSteps"), s_.steps);
    glUniform1f(march.uniform("uMeanDensity"), mean);
    setVec3(march, "uBackground", scene.background);
    bindScreenImage(binding::kScreenOutImage, terms, GL_WRITE_ONLY);
    bindScreenImage(binding::kScreenBaseImage, base, GL_READ_WRITE);
    dispatch("light-space march", {groups(w, 8), groups(h, 8), 1});
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  }
  checkGl("light-space march");
  {
    ScopedGpuTimer t(timer, "block sum");
    sum.use();
    glUniform2i(sum.uniform("uImageSize"), w, h);
    glUniform1i(sum.uniform("uInterleave"), M);
    bindScreenImage(binding::kScreenBaseImage, base, GL_READ_WRITE);
    // Horizontal: terms -> rows; vertical: rows -> out (+ base).
    glUniform1i(sum.uniform("uVertical"), 0);
    bindScreenImage(binding::kScreenInImage, terms, GL_READ_ONLY);
    bindScreenImage(binding::kScreenOutImage, rows, GL_WRITE_ONLY);
    dispatch("block sum", {groups(w, 8), groups(h, 8), 1});
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    glUniform1i(sum.uniform("uVertical"), 1);
    bindScreenImage(binding::kScreenInImage, rows, GL_READ_ONLY);
    bindScreenImage(binding::kScreenOutImage, out, GL_WRITE_ONLY);
    dispatch("block sum", {groups(w, 8), groups(h, 8), 1});
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
  }
  checkGl("block sum");
  return readScreenImage(out, w, h, OutputAlpha::Alpha, "light-space march read-back", timer);
}

void LightSpaceMarchGpu::describe(RenderStats& st) const {
  describeLightSpaceMarch(st, s_, mean_, shadowMaps_);
}

}  // namespace scatterlab::gpu
