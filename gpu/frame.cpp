#include "gpu/frame.h"

#include <algorithm>
#include <bit>
#include <limits>

#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/reconstructions.h"
#include "gpu/records.h"
#include "gpu/shaders.h"
#include "gpu/slice_marcher.h"
#include "gpu/tracing.h"
#include "gpu/volume_tracer.h"
#include "shading/transport.h"

namespace scatterlab::gpu {

GpuFrame::GpuFrame(GpuPipeline pipeline) : pipeline_(pipeline) {
  startCounts();
}

GpuFrame::GpuFrame(const DensityGrid& d) : density(uploadDensity(d)) {
  startCounts();
}

void GpuFrame::startCounts() {
  waits0_ = hostWaitCounts();
  passes0_ = passCounts();
  deferred_.clear();
}

void GpuFrame::buildDensity(const Scene& scene) {
  context();             // current before the first timer query or upload
  loopIterationLimit();  // probed once, before the first program is built
  resetLoopGuard();
  density = Volume();
  density = gpu::buildDensity(scene, &timer, &splatted_, pipeline_);
  host_.reset();
  forgetOccupancy();
}

namespace {

/// The voxel-centre → cell maps of the three axes of a `dims` grid over `voxels`
/// (voxelCells()), appended to the occupancy pass's map buffer.
void appendCellMaps(std::vector<GLint>& maps, IVec3 voxels, IVec3 dims) {
  for (const auto& [n, cells] :
       {std::pair{voxels.x, dims.x}, {voxels.y, dims.y}, {voxels.z, dims.z}})
    for (const int c : voxelCells(n, cells)) maps.push_back(c);
}

/// DensityGrid::sample(p) of an uploaded density volume, from the (up to) eight voxels around
/// p read back alone (LampModel's k_l without reading the whole volume back), in the order and
/// with the clamps of Grid3::sampleIndex.
auto densityAtPoint(const Volume& v) {
  return [&v](const Vec3& p) {
    const Vec3 cell = v.bounds.extent() / Vec3(v.dims);
    const Vec3 inv = Vec3(1.0f) / cell;
    Vec3 u = (p - v.bounds.min) * inv - 0.5f;
    const Vec3 maxIndex(v.dims - 1);
    for (int a = 0; a < 3; ++a) {
      u[a] = u[a] > 0.0f ? u[a] : 0.0f;
      u[a] = u[a] < maxIndex[a] ? u[a] : maxIndex[a];
    }
    const IVec3 b = glm::min(IVec3(u), glm::max(v.dims - 2, IVec3(0)));
    const Vec3 f = u - Vec3(b);
    const IVec3 n = glm::min(v.dims - b, IVec3(2));  // 1 along a one-voxel axis
    float c[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    countHostWait("lamp model: density around a lamp");
    glGetTextureSubImage(v.texture.id(), 0, b.x, b.y, b.z, n.x, n.y, n.z, GL_RED, GL_FLOAT,
                         GLsizei(sizeof c), c);
    const auto at = [&](int i, int j, int k) {
      return c[(std::min(k, n.z - 1) * n.y + std::min(j, n.y - 1)) * n.x + std::min(i, n.x - 1)];
    };
    const float c00 = at(0, 0, 0) + (at(1, 0, 0) - at(0, 0, 0)) * f.x;
    const float c10 = at(0, 1, 0) + (at(1, 1, 0) - at(0, 1, 0)) * f.x;
    const float c01 = at(0, 0, 1) + (at(1, 0, 1) - at(0, 0, 1)) * f.x;
    const float c11 = at(0, 1, 1) + (at(1, 1, 1) - at(0, 1, 1)) * f.x;
    const float c0 = c00 + (c10 - c00) * f.y;
    const float c1 = c01 + (c11 - c01) * f.y;
    return c0 + (c1 - c0) * f.z;
  };
}

}  // namespace

const DensityGrid& GpuFrame::hostDensity() {
  if (!host_) {
    ScopedGpuTimer t(&timer, "density read-back");
    host_ = readDensity(density);
  }
  return *host_;
}

std::vector<long long> GpuFrame::countOccupiedCells(std::span<const IVec3> grids) {
  context();
  const IVec3 nd = density.dims;
  std::vector<long long> out(grids.size(), 0);
  if (grids.empty() || nd.x <= 0 || nd.y <= 0 || nd.z <= 0) return out;
  // Each grid's bits after those of the grids counted before in this render (kept, so that
  // occupiedCellList reads the chosen grid's without a new pass).
  std::vector<GLint> table;  // per grid: dims, first word
  std::vector<GLint> maps;
  std::vector<CountedGrid> added;
  std::size_t words = cellWords_;
  for (const IVec3& dims : grids) {
    const std::size_t cells = std::size_t(dims.x) * std::size_t(dims.y) * std::size_t(dims.z);
    added.push_back({dims, words});
    table.insert(table.end(), {dims.x, dims.y, dims.z, GLint(words)});
    words += (cells + 31) / 32;
    appendCellMaps(maps, nd, dims);
  }
  if (words > std::size_t(std::numeric_limits<GLint>::max()))
    throw LimitError("the cell samplers' occupancy: " + std::to_string(words) +
                     " words of cell bits are more than a GPU buffer index reaches; a smaller "
                     "'render.sampler.count' or density resolution");
  countedGrids_.insert(countedGrids_.end(), added.begin(), added.end());
  if (cellBits_.size() < words * sizeof(GLuint)) {
    Buffer grown(Buffer::storageFor(words * sizeof(GLuint)), nullptr, 0, "cell occupancy bits");
    if (cellWords_ > 0)
      glCopyNamedBufferSubData(cellBits_.id(), grown.id(), 0, 0,
                               GLsizeiptr(cellWords_ * sizeof(GLuint)));
    cellBits_ = std::move(grown);
  }
  const GLuint zero = 0;
  glClearNamedBufferSubData(cellBits_.id(), GL_R32UI, GLintptr(cellWords_ * sizeof(GLuint)),
                            GLsizeiptr((words - cellWords_) * sizeof(GLuint)), GL_RED_INTEGER,
                            GL_UNSIGNED_INT, &zero);
  cellWords_ = words;
  const std::vector<GLuint> zeros(grids.size(), 0u);
  const Buffer counts(zeros.size() * sizeof(GLuint), zeros.data(), 0, "occupied cells");
  occupancyPass(program({.compute = {"cell_occupancy.comp.glsl"}}, "cell samplers' occupancy"),
                maps, table, counts, &cellBits_);
  std::vector<GLuint> n(grids.size());
  counts.read(n.data(), n.size() * sizeof(GLuint));  // one host wait (a cold frame's sampler)
  checkGl("cell occupancy");
  for (std::size_t g = 0; g < n.size(); ++g) out[g] = n[g];
  return out;
}

std::vector<int> GpuFrame::occupiedCellList(IVec3 dims) {
  context();
  const auto counted = [&] {
    return std::find_if(countedGrids_.rbegin(), countedGrids_.rend(),
                        [&](const CountedGrid& g) { return g.dims == dims; });
  };
  if (counted() == countedGrids_.rend()) countOccupiedCells(std::span(&dims, 1));
  const CountedGrid& grid = *counted();
  const std::size_t cells = std::size_t(dims.x) * std::size_t(dims.y) * std::size_t(dims.z);
  std::vector<GLuint> bits((cells + 31) / 32);
  std::vector<int> list;
  if (bits.empty()) return list;
  cellBits_.read(bits.data(), bits.size() * sizeof(GLuint), grid.word * sizeof(GLuint));
  for (std::size_t w = 0; w < bits.size(); ++w)
    for (GLuint b = bits[w]; b != 0; b &= b - 1)
      list.push_back(int(w * 32 + std::size_t(std::countr_zero(b))));
  return list;
}

std::vector<int> GpuFrame::occupiedVoxelsPerCell(IVec3 dims) {
  context();
  const IVec3 nd = density.dims;
  const std::size_t cells = std::size_t(dims.x) * std::size_t(dims.y) * std::size_t(dims.z);
  std::vector<int> out(cells, 0);
  if (cells == 0 || nd.x <= 0 || nd.y <= 0 || nd.z <= 0) return out;
  std::vector<GLint> maps;
  appendCellMaps(maps, nd, dims);
  const Buffer counts(cells * sizeof(GLuint), nullptr, 0, "occupied voxels per cell");
  occupancyPass(program({.compute = {"cell_occupancy.comp.glsl"}, .defines = {"SL_VOXEL_COUNTS"}},
                        "occupied voxels per cell"),
                maps, {dims.x, dims.y, dims.z, 0}, counts, nullptr);
  counts.read(out.data(), cells * sizeof(GLuint));  // one host wait, once per density
  checkGl("occupied voxels per cell");
  return out;
}

void GpuFrame::occupancyPass(const Program& p, const std::vector<GLint>& maps,
                             const std::vector<GLint>& table, const Buffer& counts,
                             const Buffer* bits) {
  const Buffer mapBuffer(maps.size() * sizeof(GLint), maps.data(), 0, "cell occupancy maps");
  const Buffer tableBuffer(table.size() * sizeof(GLint), table.data(), 0, "cell occupancy grids");
  const IVec3 nd = density.dims;
  ScopedGpuTimer t(&timer, "cell occupancy");
  p.use();
  glBindTextureUnit(binding::kDensityTexture, density.texture.id());
  mapBuffer.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
  tableBuffer.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kOffsets);
  if (bits) bits->bindBase(GL_SHADER_STORAGE_BUFFER, binding::kInSet);
  counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kCounters);
  setIVec3(p, "uVoxels", nd);
  glUniform1i(p.uniform("uGrids"), GLint(table.size() / 4));
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  dispatch("cell occupancy", {groups(nd.x, 4), groups(nd.y, 4), groups(nd.z, 4)});
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
}

void GpuFrame::forgetOccupancy() {
  countedGrids_.clear();
  cellWords_ = 0;
}

void GpuFrame::newRender() {
  context();  // the queries are deleted in the frame's context
  timer = StageTimer();
  objects = SceneShadows();
  samples.radianceCurrent = false;  // the positions and bins stay for a steady frame
  image = Texture();
  forgetOccupancy();
  marks_.clear();
  startCounts();
  resetLoopGuard();
}

std::optional<std::array<unsigned, 3>> GpuFrame::deviceImage() const {
  if (!imageOnDevice || !image) return std::nullopt;
  return std::array<unsigned, 3>{image.id(), unsigned(imageWidth), unsigned(imageHeight)};
}

void GpuFrame::sync() {
  // No glFinish: the GPU works on while the host records the next stage; each stage's GPU
  // time comes from the timer queries (gpu_timings_ms), read in report() after the frame.
  marks_.push_back(timer.count());
}

namespace {

/// The keys that make a pass's loops long, for the loop cap's error (by the program's label).
std::string loopKeys(const std::string& program) {
  const auto is = [&](const char* prefix) { return program.rfind(prefix, 0) == 0; };
  if (is("view march"))
    return "'render.march_step' (steps per view ray) and, with factored lights, the number of "
           "lights (every step adds each light's factor)";
  if (is("jittered march"))
    return "'render.steps' times the lights times 'render.delta1''s steps to each light";
  if (is("light-space march")) return "'render.steps' (steps per view ray)";
  if (is("froxel"))
    return "'render.froxel_grid' (slices per column) times the lights and their shadow steps";
  if (is("radial blur")) return "'render.march_step' and 'render.samples'";
  return "the lights times the steps to each light ('render.delta1'), and the pass's own "
         "steps";
}

}  // namespace

void GpuFrame::report(RenderStats& st) {
  const Context& ctx = context();
  // A driver that caps loop iterations (llvmpipe) ends a long march early and the shader goes on
  // with a partial sum: refuse the image rather than return it wrong (issue 37).
  if (const std::string cut = loopGuardCut(); !cut.empty())
    throw GpuError("the GPU pass '" + cut +
                   "' needed more loop iterations in one invocation "
                   "than the driver allows (" +
                   std::to_string(loopIterationLimit()) + " in all; '" + ctx.info().renderer +
                   "' ends every loop of a shader invocation there), so "
                   "its image would be wrong. What makes it long: " +
                   loopKeys(cut) + "; fewer of them, or --backend cpu, renders it");
  if (const std::string pass = fetchOutside(); !pass.empty())
    throw GpuError("the GPU pass '" + pass +
                   "' fetched a texel outside its texture (SCATTERLAB_GPU_VALIDATE): GL leaves "
                   "the value undefined, llvmpipe returns 0 and a GPU may not");
  // The frame's waits, before report() itself waits for the queries and the deferred stats.
  const HostWaitCounts waits = hostWaitCounts();
  const PassCounts passes = passCounts();
  st.extra["host_waits"] = waits.waits - waits0_.waits;
  if (waits.imageReadbacks > waits0_.imageReadbacks)
    st.extra["image_readback_ms"] = waits.imageReadbackMs - waits0_.imageReadbackMs;
  st.extra["dispatches"] = passes.dispatches - passes0_.dispatches;
  st.extra["indirect_dispatches"] = passes.indirect - passes0_.indirect;
  // This render's share of a per-pass count.
  const auto perPass = [](const std::map<std::string, long long, std::less<>>& now,
                          const std::map<std::string, long long, std::less<>>& start) {
    Json out = Json::object();
    for (const auto& [pass, n] : now) {
      const auto before = start.find(pass);
      const long long d = n - (before != start.end() ? before->second : 0);
      if (d > 0) out[pass] = d;
    }
    return out;
  };
  st.extra["dispatches_by_pass"] = perPass(passes.byPass, passes0_.byPass);
  Json invocations = perPass(passes.invocations, passes0_.invocations);
  if (invocations.contains(kTracerPass)) st.extra["tracer_invocations"] = invocations[kTracerPass];
  st.extra["invocations"] = std::move(invocations);
  for (const auto& read : deferred_) read(st);
  deferred_.clear();
  st.backend = "gpu";
  st.device = ctx.info().renderer;
  const std::vector<std::pair<std::string, double>> spans = timer.spans();
  Json gpuMs = Json::object();
  double total = 0.0;
  for (const auto& [pass, ms] : spans) {
    gpuMs[pass] = gpuMs.value(pass, 0.0) + ms;
    total += ms;
  }
  st.extra["gpu_ms"] = gpuMs;
  st.extra["gpu_ms_total"] = total;
  // One sync() per pipeline stage, in the order of timings_ms (methods/pipeline.cpp): each pass
  // belongs to the first stage whose sync came after it began.
  if (!marks_.empty() && marks_.size() == st.timingsMs.size()) {
    Json byStage = Json::object();
    std::size_t k = 0;
    for (std::size_t i = 0; i < spans.size(); ++i) {
      while (k < marks_.size() && marks_[k] <= i) ++k;
      const std::string& stage = k < marks_.size() ? st.timingsMs[k].first : "after march";
      byStage[stage] = byStage.value(stage, 0.0) + spans[i].second;
    }
    st.extra["gpu_timings_ms"] = byStage;
  }
  marks_.clear();
  st.extra["density_construction"] = splatted_ ? "gpu splat" : "cpu build + upload";
  st.extra["gl_version"] = ctx.info().version;
  st.extra["egl_platform"] = ctx.info().platform;
  if (objects.maps) {
    const ShadowMapSettings& sm = objects.maps->settings();
    st.extra["shadow_map"] = {{"type", sm.type == ShadowMapSettings::Type::Vsm ? "vsm" : "depth"},
                              {"resolution", sm.resolution},
                              {"layers", objects.maps->layers()}};
  }
}

// The stages' frame overrides: the passes on the frame's volumes, timed into its timer.

void VolumeTracerGpu::evaluate(Frame& frame, const Scene& scene, std::span<RadianceSample> samples,
                               bool gradients) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  const ShadowMaps* shadows = f.shadowMaps(scene, shadowMap_);
  if (samples.empty()) return;
  // Into the frame's resident samples: the gather reads S and ∇S where the tracer wrote them.
  f.samples.setPoints(samples);
  trace(scene, f.density, f.samples.points, samples.size(), f.samples.radiance, gradients, &f.timer,
        shadows);
  f.samples.radianceCurrent = true;
  // The host copy (RenderResult::samples, a raster splat) unless the frame stays on the device
  // with the compute gather: a Renderer frame then never waits for S and ∇S.
  if (!(f.imageOnDevice && f.pipeline() == GpuPipeline::Compute))
    readRadianceRecords(f.samples.radiance, samples);
}

ReconstructionStats GradientSplatGpu::reconstruct(Frame& frame, const Scene& scene,
                                                  std::span<const RadianceSample> samples,
                                                  IVec3 dims, Progress*) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  ReconstructionStats st;
  sigmaT_ = scene.medium.sigmaT;
  // The lamps' bound: computed by the compute gather on the GPU; the raster splat reads the
  // density around each lamp back (a host wait).
  const bool gpuLampBounds = settingsBounds_ && lamp_ && pipeline_ == GpuPipeline::Compute;
  if (settingsBounds_ && lamp_ && !gpuLampBounds)
    bounds_ =
        lampBounds(*settingsBounds_, LampModel(scene, f.density.bounds, densityAtPoint(f.density)),
                   f.density.bounds);
  else if (gpuLampBounds)
    bounds_ = settingsBounds_;
  lampScene_ = gpuLampBounds ? &scene : nullptr;
  litScene_ = factored_ ? &scene : nullptr;
  f.radiance = Volume();  // the previous render's volume goes back to the recycler first
  auto counter = std::make_shared<Buffer>();
  f.radiance = reconstruct(f.density, samples, scene.medium.bounds, dims, &st, &f.timer, &f.samples,
                           counter.get());
  // Read after the frame (GpuFrame::report), not inside it.
  lampScene_ = litScene_ = nullptr;
  const GpuBins* deviceBins = f.samples.deviceBins();
  f.deferStats([counter, deviceBins](RenderStats& st) {
    GLuint n = 0;
    counter->read(&n, sizeof n);
    st.extra["uncovered_voxels"] = n;
    // The bound on the GPU-built bins' entries is an upper bound: an overflow is a bug.
    if (deviceBins)
      if (const GLuint need = deviceBins->readOverflow())
        throw GpuError("radiance gather: the sample bins needed " + std::to_string(need) +
                       " entries, more than the bound computed for them (a bug)");
  });
  return st;
}

ReconstructionStats PerVoxelGpu::reconstruct(Frame& frame, const Scene& scene,
                                             std::span<const RadianceSample>, IVec3 dims,
                                             Progress*) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  ReconstructionStats st;
  const ShadowMaps* shadows = f.shadowMaps(scene, shadowMap_);
  f.radiance = Volume();
  auto counters = std::make_shared<Buffer>();
  f.radiance =
      build(scene, f.density, scene.medium.bounds, dims, &st, &f.timer, shadows, counters.get());
  // Read after the frame (GpuFrame::report), not inside it.
  f.deferStats([counters](RenderStats& st) {
    GpuPerVoxelCounters n;  // one read for both counts
    counters->read(&n, sizeof n);
    st.extra["traced_voxels"] = n.traced;
    st.extra["empty_voxels"] = n.skipped;
  });
  return st;
}

Image SliceMarcher::integrate(Frame& frame, const Scene& scene, Progress*) {
  GpuFrame& f = static_cast<GpuFrame&>(frame);
  f.shadowMaps(scene, shadowMap_);
  return integrate(scene, f.density, f.radiance, &f.timer, &slices_, &f.objects);
}

void SliceMarcher::describe(RenderStats& st) const {
  st.extra["gpu_pipeline"] = "raster";
  st.extra["slicing"] = raySteps_ ? "ray-steps" : "view-planes";
  st.extra["slices"] = slices_;
}

}  // namespace scatterlab::gpu
