#include "gpu/screen_march.h"

#include <vector>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/frame.h"
#include "gpu/screen_pass.h"
#include "gpu/shaders.h"
#include "gpu/tracing.h"
#include "shading/screen_march.h"

namespace scatterlab::gpu {

// ---------------------------------------------------------------- jittered march

Image JitteredMarchGpu::integrate(Frame& frame, const Scene& scene, Progress*) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  return integrate(scene, f.density, &f.timer);
}

void JitteredMarchGpu::describe(RenderStats& stats) const {
  describeJitteredMarch(stats, s_);
}

Image JitteredMarchGpu::integrate(const Scene& scene, const Volume& density, StageTimer* timer) {
  const ScreenPass pass(scene, density, delta1_, shadowMap_, timer);
  const Program& march = pass.program(
      "jittered march", {"common.glsl", "screen_common.glsl", "jittered_march.comp.glsl"});
  const Program& upsample = pass.program(
      "jittered upsample", {"common.glsl", "screen_common.glsl", "jittered_upsample.comp.glsl"});
  const Camera& cam = scene.camera;
  const int d = s_.downsample;
  const int lw = (cam.width + d - 1) / d, lh = (cam.height + d - 1) / d;
  const Texture low = Texture::make2D(GL_RGBA32F, lw, lh, "jittered march (L, T)");
  const Texture lowDepth = Texture::make2D(GL_R32F, lw, lh, "jittered march depth");
  const Texture out = Texture::make2D(GL_RGBA32F, cam.width, cam.height, "jittered march image");
  const std::vector<float>& table = blueNoiseTable();
  const Buffer tableBuf(table.size() * sizeof(float), table.data(), 0, "blue-noise table");
  {
    ScopedGpuTimer t(timer, "jittered march");
    march.use();
    pass.bind(march);
    tableBuf.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kJitterTable);
    // The lights over as many dispatches as a driver's loop cap asks (1 on a GPU without one).
    const int parts =
        lightDispatches(int(scene.lights.size()), s_.steps, diagonalSteps(scene, delta1_));
    bindScreenImage(binding::kLowResImage, low, parts > 1 ? GL_READ_WRITE : GL_WRITE_ONLY);
    glBindImageTexture(binding::kLowResDepthImage, lowDepth.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY,
                       GL_R32F);
    glUniform2i(march.uniform("uLowSize"), lw, lh);
    glUniform1i(march.uniform("uDownsample"), d);
    glUniform1i(march.uniform("uSteps"), s_.steps);
    glUniform1i(march.uniform("uJitter"), int(s_.jitter));
    glUniform1i(march.uniform("uTableSize"), kBlueNoiseSize);
    glUniform1f(march.uniform("uMinTransmittance"), minT_);
    dispatchLightParts(march, parts, "jittered march", {groups(lw, 8), groups(lh, 8), 1},
                       GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  }
  checkGl("jittered march");
  {
    ScopedGpuTimer t(timer, "bilateral upsample");
    upsample.use();
    pass.bind(upsample);
    glUniform1f(upsample.uniform("uMinTransmittance"), minT_);
    bindScreenImage(binding::kLowResImage, low, GL_READ_ONLY);
    glBindImageTexture(binding::kLowResDepthImage, lowDepth.id(), 0, GL_FALSE, 0, GL_READ_ONLY,
                       GL_R32F);
    bindScreenImage(binding::kOutputImage, out, GL_WRITE_ONLY);
    glUniform2i(upsample.uniform("uLowSize"), lw, lh);
    glUniform1i(upsample.uniform("uDownsample"), d);
    glUniform1f(upsample.uniform("uDepthSigma"), kUpsampleDepthSigma);
    setVec3(upsample, "uBackground", scene.background);
    dispatch("bilateral upsample", {groups(cam.width, 8), groups(cam.height, 8), 1});
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
  }
  checkGl("bilateral upsample");
  return readScreenImage(out, cam.width, cam.height, OutputAlpha::Transmittance, "read-back",
                         timer);
}

// ---------------------------------------------------------------- froxel

Image FroxelGpu::integrate(Frame& frame, const Scene& scene, Progress*) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  return integrate(scene, f.density, &f.timer);
}

void FroxelGpu::describe(RenderStats& stats) const {
  describeFroxel(stats, s_);
}

Image FroxelGpu::integrate(const Scene& scene, const Volume& density, StageTimer* timer) {
  const ScreenPass pass(scene, density, delta1_, shadowMap_, timer);
  const bool useMap = s_.transmittanceMap && !scene.lights.empty();
  const Program& scatter = pass.program(
      useMap ? "froxel scatter (map)" : "froxel scatter",
      {"common.glsl", "screen_common.glsl", "froxel_scatter.comp.glsl"},
      useMap ? std::vector<std::string>{"SL_TRANSMITTANCE_MAP"} : std::vector<std::string>{});
  const Program& lookup = pass.program(
      "froxel lookup", {"common.glsl", "screen_common.glsl", "froxel_lookup.comp.glsl"});
  const FroxelSlicing slicing = froxelSlicing(scene, s_);
  const Camera& cam = scene.camera;
  const IVec3 g = s_.grid;
  const int R = s_.mapResolution;
  Texture map;
  if (useMap) {
    const Program& build =
        pass.program("froxel transmittance map", {"common.glsl", "froxel_map.comp.glsl"});
    const int layers = R * int(scene.lights.size());
    map = Texture::make3D(GL_R32F, R, R, layers, "froxel transmittance maps");
    ScopedGpuTimer t(timer, "transmittance map");
    build.use();
    pass.inputs().apply(build);
    glBindImageTexture(binding::kTransmittanceMapImage, map.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY,
                       GL_R32F);
    glUniform1i(build.uniform("uMapRes"), R);
    dispatch("transmittance map", {groups(R, 4), groups(R, 4), groups(layers, 4)});
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  }
  checkGl("froxel transmittance map");
  const Texture froxels = Texture::make3D(GL_RGBA32F, g.x, g.y, g.z, "froxel volume");
  const Texture out = Texture::make2D(GL_RGBA32F, cam.width, cam.height, "froxel image");
  // The slices' boundaries as the CPU computes them (its std::pow, not the GPU's pow).
  std::vector<float> depths(std::size_t(g.z) + 1);
  for (int k = 0; k <= g.z; ++k) depths[std::size_t(k)] = slicing.depth(float(k));
  const Buffer depthBuf(depths.size() * sizeof(float), depths.data(), 0, "froxel slice depths");
  {
    ScopedGpuTimer t(timer, "froxel accumulate");
    scatter.use();
    pass.bind(scatter);
    setIVec3(scatter, "uGrid", g);
    depthBuf.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kFroxelDepths);
    // The lights over as many dispatches as a driver's loop cap asks (1 on a GPU without one):
    // a slice evaluates each light's shadow ray, or with the maps its 8 texels.
    const int parts = lightDispatches(int(scene.lights.size()), g.z,
                                      useMap ? 10.0 : diagonalSteps(scene, delta1_));
    glBindImageTexture(binding::kFroxelImage, froxels.id(), 0, GL_TRUE, 0,
                       parts > 1 ? GL_READ_WRITE : GL_WRITE_ONLY, GL_RGBA32F);
    if (useMap) {
      glBindImageTexture(binding::kTransmittanceMapImage, map.id(), 0, GL_TRUE, 0, GL_READ_ONLY,
                         GL_R32F);
      glUniform1i(scatter.uniform("uMapRes"), R);
    }
    dispatchLightParts(scatter, parts, "froxel accumulate", {groups(g.x, 8), groups(g.y, 8), 1},
                       GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  }
  checkGl("froxel accumulate");
  {
    ScopedGpuTimer t(timer, "froxel lookup");
    lookup.use();
    pass.bind(lookup);
    glUniform1f(lookup.uniform("uMinTransmittance"), minT_);
    setIVec3(lookup, "uGrid", g);
    glUniform1f(lookup.uniform("uNear"), slicing.near);
    glUniform1f(lookup.uniform("uFar"), slicing.far);
    glUniform1i(lookup.uniform("uExponential"), slicing.exponential ? 1 : 0);
    glBindImageTexture(binding::kFroxelImage, froxels.id(), 0, GL_TRUE, 0, GL_READ_ONLY,
                       GL_RGBA32F);
    bindScreenImage(binding::kOutputImage, out, GL_WRITE_ONLY);
    setVec3(lookup, "uBackground", scene.background);
    dispatch("froxel lookup", {groups(cam.width, 8), groups(cam.height, 8), 1});
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
  }
  checkGl("froxel lookup");
  return readScreenImage(out, cam.width, cam.height, OutputAlpha::Transmittance, "read-back",
                         timer);
}

}  // namespace scatterlab::gpu
