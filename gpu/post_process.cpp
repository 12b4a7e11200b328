#include "gpu/post_process.h"

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

namespace {

void bindImage(GLuint unit, const Texture& t, GLenum access) {
  glBindImageTexture(unit, t.id(), 0, GL_FALSE, 0, access, GL_RGBA32F);
}

}  // namespace

// ---------------------------------------------------------------- light-space march

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
    bindImage(binding::kScreenOutImage, terms, GL_WRITE_ONLY);
    bindImage(binding::kScreenBaseImage, base, GL_READ_WRITE);
    dispatch("light-space march", {groups(w, 8), groups(h, 8), 1});
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  }
  checkGl("light-space march");
  {
    ScopedGpuTimer t(timer, "block sum");
    sum.use();
    glUniform2i(sum.uniform("uImageSize"), w, h);
    glUniform1i(sum.uniform("uInterleave"), M);
    bindImage(binding::kScreenBaseImage, base, GL_READ_WRITE);
    // Horizontal: terms -> rows; vertical: rows -> out (+ base).
    glUniform1i(sum.uniform("uVertical"), 0);
    bindImage(binding::kScreenInImage, terms, GL_READ_ONLY);
    bindImage(binding::kScreenOutImage, rows, GL_WRITE_ONLY);
    dispatch("block sum", {groups(w, 8), groups(h, 8), 1});
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    glUniform1i(sum.uniform("uVertical"), 1);
    bindImage(binding::kScreenInImage, rows, GL_READ_ONLY);
    bindImage(binding::kScreenOutImage, out, GL_WRITE_ONLY);
    dispatch("block sum", {groups(w, 8), groups(h, 8), 1});
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
  }
  checkGl("block sum");
  return readScreenImage(out, w, h, OutputAlpha::Alpha, "light-space march read-back", timer);
}

void LightSpaceMarchGpu::describe(RenderStats& st) const {
  describeLightSpaceMarch(st, s_, mean_, shadowMaps_);
}

// ---------------------------------------------------------------- radial blur

Image RadialBlurGpu::integrate(Frame& frame, const Scene& scene, Progress*) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  return integrate(scene, f.density, &f.timer);
}

Image RadialBlurGpu::integrate(const Scene& scene, const DensityGrid& density) {
  context();
  const Volume d = uploadDensity(density);
  return integrate(scene, d, nullptr);
}

Image RadialBlurGpu::integrate(const Scene& scene, const Volume& density, StageTimer* timer) {
  checkRadialBlurScene(scene, s_);
  // delta1 is the step of the surfaces' T(p, l) (the passes trace no light otherwise).
  const ScreenPass pass(scene, density, delta1_ > 0.0f ? delta1_ : march_.step, shadowMap_, timer);
  const auto program = [&](const char* define, const char* label) -> const Program& {
    return pass.program(label, {"common.glsl", "radial_blur.comp.glsl"}, {define});
  };
  const Program& basePass = program("SL_BASE", "radial blur base");
  const Program& prePass = program("SL_PREPASS", "radial blur pre-pass");
  const Program& blur = program("SL_BLUR", "radial blur");
  const int w = scene.camera.width, h = scene.camera.height, ds = s_.downsample;
  const int pw = (w + ds - 1) / ds, ph = (h + ds - 1) / ds;
  const Texture image = Texture::make2D(GL_RGBA32F, w, h, "radial blur image");
  const Texture pre = Texture::make2D(GL_RGBA32F, pw, ph, "radial blur pre-pass");
  const auto marchUniforms = [&](const Program& p) {
    pass.bind(p);
    glUniform1f(p.uniform("uStep"), march_.step);
    glUniform1f(p.uniform("uMinTransmittance"), march_.minTransmittance);
    setVec3(p, "uBackground", scene.background);
  };
  {
    ScopedGpuTimer t(timer, "radial blur base");
    basePass.use();
    marchUniforms(basePass);
    glUniform2i(basePass.uniform("uPassSize"), w, h);
    bindImage(binding::kScreenOutImage, image, GL_WRITE_ONLY);
    dispatch("radial blur base", {groups(w, 8), groups(h, 8), 1});
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  }
  checkGl("radial blur base");
  positions_ = Json::array();
  for (int l = 0; l < int(scene.lights.size()); ++l) {
    float ax, ay;
    radialBlurLightPosition(scene, l, s_.guardBand, ax, ay);
    positions_.push_back({ax, ay});
    {
      ScopedGpuTimer t(timer, "radial blur pre-pass");
      prePass.use();
      marchUniforms(prePass);
      glUniform1i(prePass.uniform("uLight"), l);
      glUniform1i(prePass.uniform("uDownsample"), ds);
      glUniform2i(prePass.uniform("uPassSize"), pw, ph);
      bindImage(binding::kScreenOutImage, pre, GL_WRITE_ONLY);
      dispatch("radial blur pre-pass", {groups(pw, 8), groups(ph, 8), 1});
      glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }
    checkGl("radial blur pre-pass");
    {
      ScopedGpuTimer t(timer, "radial blur");
      blur.use();
      glUniform2i(blur.uniform("uImageSize"), w, h);
      glUniform2i(blur.uniform("uPreSize"), pw, ph);
      glUniform1i(blur.uniform("uDownsample"), ds);
      glUniform2f(blur.uniform("uLightPos"), ax, ay);
      glUniform1i(blur.uniform("uSamples"), s_.samples);
      glUniform1f(blur.uniform("uBlurDensity"), s_.density);
      glUniform1f(blur.uniform("uDecay"), s_.decay);
      glUniform1f(blur.uniform("uScale"), s_.exposure * s_.weight / float(s_.samples));
      bindImage(binding::kScreenInImage, pre, GL_READ_ONLY);
      bindImage(binding::kScreenBaseImage, image, GL_READ_WRITE);
      dispatch("radial blur", {groups(w, 8), groups(h, 8), 1});
      glMemoryBarrier(GL_ALL_BARRIER_BITS);
    }
    checkGl("radial blur");
  }
  return readScreenImage(image, w, h, OutputAlpha::Alpha, "radial blur read-back", timer);
}

void RadialBlurGpu::describe(RenderStats& st) const {
  describeRadialBlur(st, s_, positions_);
}

}  // namespace scatterlab::gpu
