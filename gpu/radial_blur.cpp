#include "gpu/radial_blur.h"

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
    bindScreenImage(binding::kScreenOutImage, image, GL_WRITE_ONLY);
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
      bindScreenImage(binding::kScreenOutImage, pre, GL_WRITE_ONLY);
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
      bindScreenImage(binding::kScreenInImage, pre, GL_READ_ONLY);
      bindScreenImage(binding::kScreenBaseImage, image, GL_READ_WRITE);
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
