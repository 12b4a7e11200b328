#include "gpu/slice_marcher.h"

#include <glm/gtc/type_ptr.hpp>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/screen_pass.h"
#include "gpu/shaders.h"

namespace scatterlab::gpu {

namespace {

/// NDC z of view depth z under cameraViewProj(nearD, farD).
float ndcDepth(float z, float nearD, float farD) {
  z = std::max(z, nearD);
  return (farD + nearD) / (farD - nearD) - 2.0f * farD * nearD / ((farD - nearD) * z);
}

/// The slice marcher's program: ray-step layers or the paper's view-plane slabs, with the light
/// factor and the objects' shadow-map variant as asked.
const Program& sliceMarchProgram(bool raySteps, bool factor, bool lamp, const ShadowMaps* shadows) {
  ProgramVariant variant{.vertex = {"fullscreen.vert.glsl"},
                         .fragment = {"common.glsl", "slice_march.frag.glsl"}};
  variant.define("SL_RAY_STEPS", raySteps)
      .define("SL_FACTOR_LIGHTS", factor)
      .define("SL_LAMP_MODEL", factor && lamp);
  return program(addShadowVariant(shadows, variant), "slice marcher");
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
  const TracingInputs inputs(scene, density, surfaces ? delta1_ : 0.0f, shadows, timer);
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
    glUniform1f(program.uniform("uGlow"), settings_.glow ? 1.0f : 0.0f);
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
