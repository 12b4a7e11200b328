#include "gpu/view_march.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "gpu/bindings.h"
#include "gpu/dispatch.h"
#include "gpu/frame.h"
#include "gpu/records.h"
#include "gpu/screen_pass.h"
#include "gpu/shaders.h"
#include "gpu/volume.h"

namespace scatterlab::gpu {

namespace {

/// A's far field updated in place (ViewMarchGpu::integrate) for at most this many changed
/// lights (far_field.comp.glsl's uChanged[]), and at most this many times in a row before it is
/// built whole (each update adds a rounding of the sums, as FarFieldCache::kMaxUpdates).
constexpr int kMaxFarChanged = 32;
constexpr int kMaxFarUpdates = 16;

}  // namespace

Image ViewMarchGpu::integrate(Frame& frame, const Scene& scene, Progress*) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  auto counters = std::make_shared<Buffer>();
  // Read after the frame (GpuFrame::report), not inside it.
  f.deferStats([counters](RenderStats& st) {
    GpuMarchCounters n;
    counters->read(&n, sizeof n);
    st.extra["march_steps"] = GpuMarchCounters::join(n.looked);
    st.extra["march_steps_skipped"] = GpuMarchCounters::join(n.skipped);
  });
  Image img;
  if (!f.imageOnDevice) {
    img = integrate(scene, f.density, f.radiance, &f.timer, nullptr, counters.get());
  } else {
    f.imageWidth = scene.camera.width;
    f.imageHeight = scene.camera.height;
    img = integrate(scene, f.density, f.radiance, &f.timer, &f.image, counters.get());
  }
  if (farTermsPerVertex_ >= 0)
    f.deferStats([counter = farCounter_, perVertex = farTermsPerVertex_](RenderStats& st) {
      std::uint32_t vertices = 0;
      if (counter) counter->read(&vertices, sizeof vertices);
      st.extra["far_field_terms"] = (long long)(vertices)*perVertex;
    });
  return img;
}

void ViewMarchGpu::describe(RenderStats& stats) const {
  stats.extra["gpu_pipeline"] = "compute";
}

Image ViewMarchGpu::integrate(const Scene& scene, const DensityGrid& density,
                              const RadianceGrid& radiance) {
  const Volume d = uploadDensity(density);
  const Volume r = uploadRadiance(radiance);
  return integrate(scene, d, r, nullptr);
}

Image ViewMarchGpu::integrate(const Scene& scene, const Volume& density, const Volume& radiance,
                              StageTimer* timer, Texture* keep, Buffer* counters) {
  // The surfaces' T(p, l) is traced with delta1 (the slice marcher's and CPU's convention).
  ScreenPass pass(scene, density, delta1_, shadowMap_, timer);
  std::vector<std::string> defines;
  std::vector<std::string> files = {"common.glsl", "screen_common.glsl", "view_march.comp.glsl"};
  if (skipEmpty_) {
    defines.push_back("SL_SKIP");
    files.insert(files.end() - 1, "block_walk.glsl");
  }
  if (factor_) defines.push_back("SL_FACTOR_LIGHTS");
  if (factor_ && lamp_) defines.push_back("SL_LAMP_MODEL");
  // A's far field (render.far_field): one pass writes the grid of far terms Σ_l w_l·A_l, a vertex
  // per voxel corner of the medium's box (FarFieldCache on the CPU, cpu/far_field.h), which the
  // march reads.
  const bool far = factor_ && settings_.farField > 0.0f;
  const Medium& medium = scene.medium;
  const IVec3 farDims = medium.resolution + IVec3(1);
  const float farR = settings_.farField * medium.voxelSize();
  const Vec3 farCell = medium.bounds.extent() / Vec3(medium.resolution);
  const auto setFar = [&](const Program& p, const std::string& prefix) {
    glUniform1f(p.uniform(prefix + "R"), farR);
    setVec3(p, prefix + "Lo", medium.bounds.min);
    setVec3(p, prefix + "Cell", farCell);
    setIVec3(p, prefix + "Dims", farDims);
  };
  // The bricks of the lights' masks (far_mask.comp.glsl): kFarBrick³ cells, words of 32 lights.
  const IVec3 farBricks = (medium.resolution + IVec3(kFarBrick - 1)) / kFarBrick;
  const int farWords = int((scene.lights.size() + 31) / 32);
  // Kept with the lights (DeviceLights::farField) while they, the density, R and the lamp
  // model stay: a frame that moved only the camera runs no pass. Where some lamps moved (at most
  // half of them, kMaxFarChanged), the grid of the lights before is taken over and updated in
  // place: their old terms taken out (a pass over the old lights), their new ones put in; whole
  // again after kMaxFarUpdates updates (FarFieldCache on the CPU, cpu/far_field.h, alike).
  const DeviceLights& lights = pass.inputs().lights();
  const Texture& farGrid = lights.farField;
  farTermsPerVertex_ = far ? 0 : -1;
  farCounter_.reset();
  // The far field's passes compute only the vertices a step can read (SL_FAR_SKIP), from the
  // empty-space grid the march walks; built by the density's first march, bound by apply.
  if (skipEmpty_) pass.skipEmptySpace(timer);
  if (far && !(farGrid.id() && lights.farFieldRadius == farR && lights.farFieldLamp == lamp_)) {
    std::vector<int> changed;
    const DeviceLights* before = lights.before.get();
    bool update = before && before->farField.id() && before->farFieldRadius == farR &&
                  before->farFieldLamp == lamp_ && before->farFieldDims == farDims &&
                  before->farFieldUpdates < kMaxFarUpdates;
    for (std::size_t l = 0; update && l < lights.packed.size(); ++l) {
      const GpuLight &a = lights.packed[l], &b = before->packed[l];
      if (std::memcmp(&a, &b, sizeof a) == 0) continue;
      changed.push_back(int(l));
      update = a.type == b.type && int(changed.size()) <= kMaxFarChanged &&
               2 * changed.size() <= lights.packed.size();
    }
    std::vector<std::string> farDefines;
    if (lamp_) farDefines.push_back("SL_LAMP_MODEL");
    if (update) farDefines.push_back("SL_FAR_UPDATE");
    if (skipEmpty_) farDefines.push_back("SL_FAR_SKIP");
    std::vector<std::string> farFiles = {"common.glsl", "far_field.comp.glsl"};
    if (skipEmpty_) farFiles.insert(farFiles.end() - 1, "block_walk.glsl");
    const Program& fp =
        pass.program(update ? "far field update" : "far field", farFiles, farDefines);
    ScopedGpuTimer t(timer, update ? "far field update" : "far field");
    fp.use();
    pass.inputs().apply(fp);  // the lights and the medium's uniforms (no camera: A is isotropic)
    setFar(fp, "uBuild");
    const UVec3 farGroups(groups(std::size_t(farDims.x), 4), groups(std::size_t(farDims.y), 4),
                          groups(std::size_t(farDims.z), 4));
    const std::uint32_t zero = 0;
    farCounter_ = std::make_shared<Buffer>(sizeof zero, &zero, 0, "far field count");
    farCounter_->bindBase(GL_SHADER_STORAGE_BUFFER, binding::kCounters);
    if (update) {
      lights.farField = std::move(before->farField);
      lights.farFieldUpdates = before->farFieldUpdates + 1;
      glBindImageTexture(binding::kFarFieldImage, farGrid.id(), 0, GL_TRUE, 0, GL_READ_WRITE,
                         GL_RGBA32F);
      glUniform1i(fp.uniform("uChangedCount"), GLint(changed.size()));
      glUniform1iv(fp.uniform("uChanged"), GLsizei(changed.size()), changed.data());
      // The old terms out with the old lights (and their lamp model's k), the new ones in.
      before->buffer.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLights);
      glUniform1f(fp.uniform("uSign"), -1.0f);
      dispatch("far field update", farGroups);
      glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
      lights.buffer.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLights);
      glUniform1f(fp.uniform("uSign"), 1.0f);
      dispatch("far field update", farGroups);
      farTermsPerVertex_ = std::count_if(changed.begin(), changed.end(),
                                         [&](int l) { return lights.packed[l].type == 0.0f; });
    } else {
      // Every texel stored by the pass (0 where no step reads it).
      lights.farField = Texture::make3D(GL_RGBA32F, farDims.x, farDims.y, farDims.z, "far field",
                                        Texture::Contents::Overwritten);
      lights.farFieldUpdates = 0;
      glBindImageTexture(binding::kFarFieldImage, farGrid.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY,
                         GL_RGBA32F);
      dispatch("far field", farGroups);
      farTermsPerVertex_ = std::count_if(lights.packed.begin(), lights.packed.end(),
                                         [](const GpuLight& l) { return l.type == 0.0f; });
    }
    // The march's texelFetch, and the counter's read after the frame, see the writes.
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                    GL_SHADER_STORAGE_BARRIER_BIT);
    // The lights' masks per brick, for these lights: every spot and directional light, and the
    // point lights within 2R of the brick (timed with the grid's pass).
    {
      const Program& mp = pass.program("far field masks", {"common.glsl", "far_mask.comp.glsl"});
      mp.use();
      pass.inputs().apply(mp);
      lights.farMask = Buffer(std::size_t(farBricks.x) * std::size_t(farBricks.y) *
                                  std::size_t(farBricks.z) * std::size_t(farWords) * 4,
                              nullptr, 0, "far field masks");
      lights.farMask.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kFarMaskOut);
      glUniform1f(mp.uniform("uMaskR"), farR);
      setVec3(mp, "uMaskLo", medium.bounds.min);
      setVec3(mp, "uMaskCell", farCell);
      setIVec3(mp, "uMaskBricks", farBricks);
      glUniform1i(mp.uniform("uMaskWords"), farWords);
      dispatch("far field masks",
               UVec3(groups(std::size_t(farBricks.x), 4), groups(std::size_t(farBricks.y), 4),
                     groups(std::size_t(farBricks.z), 4)));
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
    lights.farFieldRadius = farR;
    lights.farFieldLamp = lamp_;
    lights.farFieldDims = farDims;
  }
  lights.before.reset();
  if (far) defines.push_back("SL_FAR_FIELD");
  if (radiance.densityInAlpha && sameGrid(density, radiance.bounds, radiance.dims))
    defines.push_back("SL_FUSED");
  const Program& march = pass.program("view march", files, defines);
  // The steps looked up and jumped over (GpuMarchCounters), zero before the pass.
  const GpuMarchCounters zero;
  Buffer own;
  if (!counters) counters = &own;
  *counters = Buffer(sizeof zero, &zero, 0, "view march counters");
  const Camera& cam = scene.camera;
  Texture out = Texture::make2D(GL_RGBA32F, cam.width, cam.height, "view march image",
                                Texture::Contents::Overwritten);  // one store per pixel
  const int strata = std::max(1, int(std::lround(std::sqrt(double(cam.spp)))));
  // Built by the density's first march (its own pass, timed apart; above); bound by pass.bind.
  {
    ScopedGpuTimer t(timer, "view march");
    march.use();
    pass.bind(march);
    glBindTextureUnit(binding::kRadianceTexture, radiance.texture.id());
    setVec3(march, "uRadScale", radiance.indexScale());
    setVec3(march, "uRadOffset", radiance.indexOffset());
    setIVec3(march, "uRadDims", radiance.dims);
    glUniform1f(march.uniform("uStep"), settings_.step);
    glUniform1f(march.uniform("uMinT"), settings_.minTransmittance);
    glUniform1f(march.uniform("uGlow"), settings_.glow ? 1.0f : 0.0f);
    if (far) {
      setFar(march, "uFar");
      glBindTextureUnit(binding::kFarFieldTexture, farGrid.id());
      lights.farMask.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kFarMask);
      setIVec3(march, "uFarBricks", farBricks);
      glUniform1i(march.uniform("uFarWords"), farWords);
    }
    glUniform1i(march.uniform("uStrata"), strata);
    setVec3(march, "uBackground", scene.background);
    counters->bindBase(GL_SHADER_STORAGE_BUFFER, binding::kCounters);
    // With factored lights every step evaluates each light's term of A (and a few substeps near
    // a lamp, the glow): where the driver caps loops, the lights over as many dispatches as it
    // asks, each adding its part (1 on a GPU without a cap). The steps of the longest ray: the
    // box's diagonal at the march's step, for each of the strata.
    const double steps = double(strata) * double(strata) * diagonalSteps(scene, settings_.step);
    const int parts = factor_ ? lightDispatches(int(scene.lights.size()), steps, 2.0) : 1;
    bindScreenImage(binding::kOutputImage, out, parts > 1 ? GL_READ_WRITE : GL_WRITE_ONLY);
    const UVec3 size(groups(cam.width, 8), groups(cam.height, 8), 1);
    const GLbitfield barrier = GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT;
    if (factor_) {  // only the factored variant declares the parts' uniforms
      dispatchLightParts(march, parts, "view march", size, barrier);
    } else {
      dispatch("view march", size);
      glMemoryBarrier(barrier);
    }
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  }
  checkGl("view march");
  if (keep) {
    // Whoever samples or copies it next sees the writes.
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                    GL_PIXEL_BUFFER_BARRIER_BIT);
    *keep = std::move(out);
    return Image();
  }
  return readScreenImage(out, cam.width, cam.height, OutputAlpha::Alpha, "view march read-back",
                         timer);
}

}  // namespace scatterlab::gpu
