/// The GPU variants of the real-time methods (gpu/light_space_march.h, gpu/radial_blur.h) against
/// their CPU twins (cpu/light_space_march.h, cpu/radial_blur.h), end to end through createMethod,
/// on llvmpipe in CI; and what the GPU variants refuse (a light behind the camera).

#include "core/method.h"
#include "gpu/context.h"
#include "gpu/gl.h"
#include "gpu_support.h"

namespace scatterlab::testing {
namespace {

/// Renders `scene` with `render` on both backends; returns the relative L2 of GPU vs CPU and
/// checks the stats name the backends.
double gpuVsCpu(Scene scene, const Json& render) {
  scene.render = render;
  const RenderResult cpu = createMethod(scene, "", "cpu")->render(scene, nullptr);
  const RenderResult gpu = createMethod(scene, "", "gpu")->render(scene, nullptr);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  EXPECT_EQ(cpu.stats.backend, "cpu");
  EXPECT_EQ(gpu.stats.backend, "gpu");
  EXPECT_EQ(gpu.stats.device, gpu::context().info().renderer);
  EXPECT_EQ(gpu.image.alpha().size(), cpu.image.alpha().size());
  double alpha = 0.0;
  for (std::size_t i = 0; i < cpu.image.alpha().size(); ++i)
    alpha = std::max(alpha, double(std::abs(gpu.image.alpha()[i] - cpu.image.alpha()[i])));
  EXPECT_LT(alpha, 1e-5) << "alpha";
  return relL2(gpu.image, cpu.image);
}

TEST(GpuLightSpaceMarch, MatchesCpu) {
  SCATTERLAB_REQUIRE_GPU();
  const Scene scene = sceneFromJson(blobSceneDoc(20, 32, 24));
  // Measured on llvmpipe: 2.24e-6 (mean, M = 4), 7.4e-7 (traced, M = 1), 1.84e-6 (traced,
  // M = 2): float transcendental functions and summation order only. On an NVIDIA H200 (driver
  // 580), 2026-11, issue 23: 2.1e-6 for traced, M = 1 (hardware exp); the others within 1.5x
  // llvmpipe's. The limit is 1.5x the larger of the two.
  const std::vector<std::pair<Json, double>> cases = {
      {{{"light_transmittance", "mean"}, {"steps", 64}, {"interleave", 4}}, 2.24e-6},
      {{{"light_transmittance", "traced"}, {"steps", 32}, {"interleave", 1}}, 2.1e-6},
      {{{"light_transmittance", "traced"}, {"steps", 48}, {"interleave", 2}}, 1.84e-6}};
  for (const auto& [keys, measured] : cases) {
    Json render = {{"method", "light-space-march"}};
    render.update(keys);
    const double err = gpuVsCpu(scene, render);
    std::printf("light-space-march gpu vs cpu %s: relative L2 %.3g\n", keys.dump().c_str(), err);
    EXPECT_LT(err, measured * 1.5) << keys.dump();
  }
}

TEST(GpuRadialBlur, MatchesCpu) {
  SCATTERLAB_REQUIRE_GPU();
  Json doc = blobSceneDoc(20, 32, 24);
  // Both lights: the point light in view behind the medium (radial-blur refuses it inside), the
  // spot just above the image (off screen).
  doc["lights"][0]["position"] = {0.55, 0.55, 1.4};
  const Scene scene = sceneFromJson(doc);
  // Measured on llvmpipe, 2026-11-28 (the light behind the medium): 8.16e-8 (full-resolution
  // pre-pass), 1.28e-7 (downsample 2, decay 0.95). (With the light inside, before radial-blur
  // refused it: 1.37e-6 and 1.61e-6, and on an NVIDIA H200 below the 1.5× of those, 2026-11-27.)
  // About one ulp per pixel: hardware's exp, sqrt and division round differently, so the bound
  // carries the hardware factor (unmeasuredOnHardware) until this case is measured there.
  const std::vector<std::pair<Json, double>> cases = {
      {{{"samples", 32}}, 8.16e-8},
      {{{"samples", 24}, {"downsample", 2}, {"decay", 0.95}, {"density", 0.6}}, 1.28e-7}};
  for (const auto& [keys, measured] : cases) {
    Json render = {{"method", "radial-blur"}, {"march_step", 1.0 / 40}};
    render.update(keys);
    const double err = gpuVsCpu(scene, render);
    std::printf("radial-blur gpu vs cpu %s: relative L2 %.3g\n", keys.dump().c_str(), err);
    EXPECT_LT(err, unmeasuredOnHardware(measured)) << keys.dump();
  }
}

TEST(GpuRealtimeMethods, RefuseWhatTheyCannotRender) {
  SCATTERLAB_REQUIRE_GPU();
  // No image from a light behind the camera, on the GPU as on the CPU.
  Json doc = blobSceneDoc(12, 16, 12);
  doc["lights"] =
      Json::array({{{"type", "point"}, {"position", {0.5, 0.5, -3}}, {"intensity", 1}}});
  Scene s = sceneFromJson(doc);
  s.render = {{"method", "radial-blur"}};
  auto m = createMethod(s, "", "gpu");
  try {
    m->render(s, nullptr);
    ADD_FAILURE() << "rendered a light behind the camera";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("behind the camera"), std::string::npos) << e.what();
  }
  // Nor from a light inside the medium (an UnsupportedSceneError, as on the CPU).
  s.lights[0].position = Vec3(0.5f, 0.5f, 0.5f);
  try {
    createMethod(s, "", "gpu")->render(s, nullptr);
    ADD_FAILURE() << "rendered a light inside the medium";
  } catch (const UnsupportedSceneError& e) {
    EXPECT_NE(std::string(e.what()).find("inside the medium's box"), std::string::npos) << e.what();
  }
  // Objects render on the GPU (tests/gpu/test_competitor_objects.cpp): nothing refused.
}

}  // namespace
}  // namespace scatterlab::testing
