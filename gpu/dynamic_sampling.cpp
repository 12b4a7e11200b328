#include "gpu/dynamic_sampling.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <string>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/empty_space.h"
#include "gpu/scan.h"
#include "gpu/shaders.h"
#include "gpu/volume_tracer.h"

namespace scatterlab::gpu {

namespace {

/// The geometry of G_{k+1} as GridInfoBuffer computes it (bounds, dims, interval, radius), without
/// its host arrays (the membership and ancestors live on the GPU).
struct GridGeometry {
  Box bounds;
  IVec3 dims;
  Vec3 interval;
  float R;
  bool voxels, cells;
  GridGeometry(const Box& b, const LevelGrid& g) {
    bounds = b;
    voxels = g.voxels;
    cells = g.cells;
    dims = g.dims;
    interval = g.voxels || g.dims.x != g.dims.y || g.dims.y != g.dims.z
                   ? b.extent() / Vec3(g.dims)
                   : b.extent() / float(g.dims.x);
    R = g.voxels ? 0.5f * std::min(interval.x, std::min(interval.y, interval.z))
                 : std::max(interval.x, std::max(interval.y, interval.z));
  }
  std::size_t vertices() const { return std::size_t(dims.x) * dims.y * dims.z; }
  float radius() const { return R; }
};

/// The grid of G_{k+1} as split and compact read it (GridInfoBuffer::vertex's convention).
void setGridUniforms(const Program& p, const GridGeometry& grid) {
  setVec3(p, "uGridMin", grid.bounds.min);
  setVec3(p, "uGridInterval", grid.interval);
  setIVec3(p, "uGridDims", grid.dims);
}

std::string levelLabel(const char* what, std::size_t level) {
  return std::string("dynamic sampling ") + what + " (level " + std::to_string(level) + ")";
}

/// Layout of DynamicSamplingWorkspace::counts for L split levels: [0, L] the levels' sample
/// counts, [L + 1] the largest count a level asked for beyond its capacity, [L + 2] that level,
/// then from dispatchSlot(L) three uints (x, 1, 1) per level: its evaluate/split dispatch.
std::size_t overflowSlot(std::size_t L) {
  return L + 1;
}
std::size_t dispatchSlot(std::size_t L) {
  return L + 3;
}

/// Sums per sample of the probe pass: the groups of kProbeGroup probes (`probes`: the most of
/// any level, the buffer's size; a level's own count: levelProbes()).
int probeGroups(int probes) {
  return (probes + kProbeGroup - 1) / kProbeGroup;
}

/// The passes of a level after the tracer's (gpu/shaders/dynamic_error.comp.glsl): evaluation,
/// probes, combination.
enum class ErrorPass { Evaluate, Probes, Combine };

/// What the level's values are: V = S / A (factored lights) with A's lamp model, ln V. A's model
/// is the samples' (steps.lampModel): ErrorSpace::lampModel is the same flag.
TracerVariant valueSpace(const TracerSteps& steps, bool gradients) {
  return {.gradients = gradients,
          .factorLights = steps.factorLights,
          .lampModel = steps.factorLights && steps.lampModel,
          .logSpace = steps.logValues()};
}

/// The probe pass's layout: the tracer's lanes over the lights, a row per probe of a group.
TracerShape probeShape(std::size_t lights) {
  TracerShape s = tracerShape(lights, false);
  s.rows = kProbeGroup;
  return s;
}

const Program& errorProgram(const TracingInputs& inputs, const TracerSteps& steps,
                            const DynamicSamplingSettings& settings, ErrorPass pass,
                            std::size_t lights) {
  if (pass == ErrorPass::Combine)
    return program(
        {.compute = {"common.glsl", "dynamic_error.comp.glsl"}, .defines = {"SL_COMBINE"}},
        "dynamic sampling error (combine)");
  const TracerVariant space = valueSpace(steps, false);
  ProgramVariant variant;
  if (pass == ErrorPass::Probes) {
    variant = tracerProgramVariant(probeShape(lights), space);
    variant.define("SL_PROBES");
  } else {
    variant.compute = {"common.glsl", "dynamic_error.comp.glsl"};
    variant.define("SL_FACTOR_LIGHTS", space.factorLights)
        .define("SL_LAMP_MODEL", space.lampModel)
        .define("SL_LOG_SPACE", space.logSpace);
    addShadowRaySkip(variant);
  }
  variant.define("SL_BOUNDED", bool(settings.space.bounds))
      .define("SL_WEIGHT_A", settings.space.weightA && steps.factorLights);
  return program(addShadowVariant(inputs.shadows(), variant), pass == ErrorPass::Probes
                                                                  ? "dynamic sampling probes"
                                                                  : "dynamic sampling evaluate");
}

/// Sizes the workspace for `n0` initial samples and `levels`, and uploads level 0 (positions,
/// radii, each sample its own ancestor) and the counts (n0, zeros).
void prepareWorkspace(DynamicSamplingWorkspace& w, const std::vector<RadianceSample>& initial,
                      const DynamicSamplingSettings& settings) {
  const std::vector<LevelGrid> grids = levelGrids(settings);
  const auto gridVertices = [&](std::size_t k) {
    const IVec3 d = grids[k].dims;
    return std::size_t(d.x) * std::size_t(d.y) * std::size_t(d.z);
  };
  const std::size_t L = grids.size(), n0 = initial.size();
  if (w.levels.size() < L + 1) w.levels.resize(L + 1);
  for (std::size_t k = 0; k <= L; ++k) {
    std::size_t cap = n0;
    if (k > 0) cap = std::min(gridVertices(k - 1), w.maxLevelSamples);
    DynamicSamplingWorkspace::Level& l = w.levels[k];
    l.capacity = cap;
    ensure(l.samples, cap * sizeof(GpuSamplePoint), levelLabel("samples", k));
    ensure(l.ancestors, cap * sizeof(std::int32_t), levelLabel("ancestors", k));
    ensure(l.radiance, cap * sizeof(GpuRadianceRecord), levelLabel("S", k));
    ensure(l.errors, (k == 0 ? 2 : 1) * cap * sizeof(float), levelLabel("E", k));
  }
  std::size_t vertices = 0;
  for (std::size_t k = 0; k < L; ++k) vertices = std::max(vertices, gridVertices(k));
  if (vertices > w.vertices) {
    ensure(w.inSet, vertices * sizeof(GLuint), "grid info: in set");
    ensure(w.vertexAncestors, vertices * sizeof(std::int32_t), "grid info: ancestor");
    ensure(w.offsets, vertices * sizeof(GLuint), "grid info: offsets");
    w.vertices = vertices;
  }
  ensure(w.threshold, 2 * sizeof(double), "dynamic sampling threshold");
  ensure(w.rootTau, n0 * sizeof(float), "dynamic sampling root tau");
  std::size_t probed = 0;  // the largest level that is probed (all but the last)
  for (std::size_t k = 0; k < L; ++k) probed = std::max(probed, w.levels[k].capacity);
  ensure(w.probeSums, probed * std::size_t(probeGroups(settings.probes)) * sizeof(float),
         "dynamic sampling probe sums");
  const std::size_t words = dispatchSlot(L) + 3 * (L + 1);
  ensure(w.counts, words * sizeof(GLuint), "dynamic sampling counts");
  std::vector<GLuint> counts(words, 0u);
  counts[0] = GLuint(n0);
  glNamedBufferSubData(w.counts.id(), 0, GLsizeiptr(words * sizeof(GLuint)), counts.data());
  std::vector<GpuSamplePoint> points;
  points.reserve(n0);
  std::vector<std::int32_t> anc(n0);
  for (std::size_t i = 0; i < n0; ++i) {
    points.push_back({initial[i].position, initial[i].radius});
    anc[i] = std::int32_t(i);
  }
  if (n0) {
    glNamedBufferSubData(w.levels[0].samples.id(), 0, GLsizeiptr(n0 * sizeof(GpuSamplePoint)),
                         points.data());
    glNamedBufferSubData(w.levels[0].ancestors.id(), 0, GLsizeiptr(n0 * sizeof(std::int32_t)),
                         anc.data());
  }
  checkGl("dynamic sampling: upload level 0");
}

/// One invocation per sample of level k: level 0's size is known on the host (its capacity);
/// a later level's is the dispatch size the count pass left in w.counts (no read-back).
void dispatchOverLevel(const char* pass, const DynamicSamplingWorkspace& w, std::size_t k,
                       std::size_t L) {
  if (k == 0) {
    dispatch(pass, {groups(w.levels[0].capacity, 64), 1, 1});
    return;
  }
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, w.counts.id());
  dispatchIndirect(pass, GLintptr((dispatchSlot(L) + 3 * k) * sizeof(GLuint)));
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
}

/// How a level is evaluated: split level (S, ∇S, E_j), final (S, ∇S), or final without ∇S
/// (the per-voxel fallback's voxels).
enum class Evaluation { Split = 0, Final = 1, FinalNoGradient = 2 };

/// Evaluate level k (its count on the GPU after level 0): S and ∇S by the tracer's pass
/// (traceLevel); unless final, then (dynamic_error.comp.glsl) τ and on level 0 the
/// contributions, the probes in groups of kProbeGroup, and E_j. GPU time: "ds evaluate+error".
void evaluateLevel(DynamicSamplingWorkspace& w, const TracingInputs& inputs, const Volume& density,
                   std::size_t lights, std::size_t k, Evaluation mode, const TracerSteps& steps,
                   const DynamicSamplingSettings& settings, StageTimer* timer) {
  const Vec3* dirs = probeOffsets();  // the CPU's probe offsets of a unit sphere
  const DynamicSamplingWorkspace::Level& l = w.levels[k];
  const std::vector<LevelGrid> grids = levelGrids(settings);
  const std::size_t L = grids.size();
  // The level's probes: fewer on the level the per-voxel fallback follows (levelProbes()).
  const int probes = k < L ? levelProbes(settings, grids[k]) : settings.probes;
  const GLint groupsPerSample = probeGroups(probes);
  ScopedGpuTimer t(timer, "ds evaluate+error");
  // pass 0: S and ∇S, parallel over (sample, point, light) (∇S = 0 for the per-voxel fallback's
  // voxels, as the CPU's gradients = false)
  traceLevel(inputs, lights, valueSpace(steps, mode != Evaluation::FinalNoGradient), steps.delta2,
             l.samples, l.radiance, w.counts, k, l.capacity);
  if (mode != Evaluation::Split) {  // a final level has S and ∇S, and no E
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    return;
  }
  {  // pass 1: τ, the contributions
    const Program& program = errorProgram(inputs, steps, settings, ErrorPass::Evaluate, lights);
    program.use();
    inputs.apply(program);
    glUniform1ui(program.uniform("uLevel"), GLuint(k));
    glUniform3fv(program.uniform("uProbeDirs"), kMaxProbes, &dirs[0].x);
    glUniform1i(program.uniform("uTauMode"), k == 0 ? 0 : (settings.perSampleTau ? 2 : 1));
    glUniform1f(program.uniform("uTauDelta1"), settings.delta1);
    glUniform1i(program.uniform("uVisibleTau"), settings.visibleTau ? 1 : 0);
    setVec3(program, "uDensityInvCell", Vec3(1.0f) / density.cellSize());
    l.samples.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
    l.ancestors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kAncestors);
    w.rootTau.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRootTau);
    l.radiance.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRadiance);
    l.errors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kErrors);
    w.counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
    dispatchOverLevel("ds evaluate", w, k, L);
  }
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  {  // pass 2: parallel over (sample, probe, light); a workgroup's y is its group of probes
    const Program& program = errorProgram(inputs, steps, settings, ErrorPass::Probes, lights);
    program.use();
    inputs.apply(program);
    glUniform1ui(program.uniform("uLevel"), GLuint(k));
    glUniform1i(program.uniform("uProbes"), probes);
    glUniform3fv(program.uniform("uProbeDirs"), kMaxProbes, &dirs[0].x);
    if (settings.space.bounds)
      glUniform2f(program.uniform("uTaylorBounds"), settings.space.bounds->lo,
                  settings.space.bounds->hi);
    setVec3(program, "uDensityInvCell", Vec3(1.0f) / density.cellSize());
    l.samples.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
    l.radiance.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRadiance);
    w.counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
    w.probeSums.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kProbeSums);
    // The count is known only on the GPU: workgroups for the level's capacity, at most 4096
    // along x; they stride over the samples (as traceLevel).
    const TracerShape shape = probeShape(lights);
    dispatch("ds probes", {std::min<GLuint>(groups(l.capacity, GLuint(shape.slots)), 4096u),
                           GLuint(groupsPerSample), 1});
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
  {  // pass 3: E_j from the groups' sums
    const Program& program = errorProgram(inputs, steps, settings, ErrorPass::Combine, lights);
    program.use();
    glUniform1ui(program.uniform("uLevel"), GLuint(k));
    glUniform1i(program.uniform("uProbes"), probes);
    glUniform1i(program.uniform("uProbeGroups"), groupsPerSample);
    l.samples.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
    l.errors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kErrors);
    w.counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
    w.probeSums.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kProbeSums);
    dispatchOverLevel("ds combine", w, k, L);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  }
}

/// Level 0: the error scale (mean contribution, in double) and the absolute threshold, left in
/// w.threshold. GPU time: "ds threshold".
void computeThreshold(DynamicSamplingWorkspace& w, const DynamicSamplingSettings& settings,
                      StageTimer* timer) {
  const Program& program =
      gpu::program({.compute = {"dynamic_level.comp.glsl"}, .defines = {"SL_THRESHOLD"}},
                   "dynamic sampling threshold");
  ScopedGpuTimer t(timer, "ds threshold");
  program.use();
  glUniform1d(program.uniform("uEpsilon"), settings.epsilon);
  glUniform1i(program.uniform("uRelative"), settings.relative ? 1 : 0);
  w.counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
  w.levels[0].errors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kErrors);
  w.threshold.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kThreshold);
  dispatch("ds threshold", {1, 1, 1});
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
}

/// Split level k into the grid information buffer of G_{k+1} (cleared first). GPU time:
/// "ds split".
void splitLevel(DynamicSamplingWorkspace& w, const GridGeometry& grid, std::size_t k, std::size_t L,
                StageTimer* timer) {
  const Program& program =
      gpu::program({.compute = {"dynamic_split.comp.glsl"}}, "dynamic sampling split");
  const std::size_t nv = grid.vertices();
  const GLuint zero = 0;
  const GLint none = INT_MAX;
  ScopedGpuTimer t(timer, "ds split");
  glClearNamedBufferSubData(w.inSet.id(), GL_R32UI, 0, GLsizeiptr(nv * sizeof(GLuint)),
                            GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  glClearNamedBufferSubData(w.vertexAncestors.id(), GL_R32I, 0, GLsizeiptr(nv * sizeof(GLint)),
                            GL_RED_INTEGER, GL_INT, &none);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  const DynamicSamplingWorkspace::Level& l = w.levels[k];
  program.use();
  glUniform1ui(program.uniform("uLevel"), GLuint(k));
  setGridUniforms(program, grid);
  glUniform1i(program.uniform("uCell"), grid.voxels || grid.cells ? 1 : 0);
  l.samples.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
  l.ancestors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kAncestors);
  l.errors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kErrors);
  w.counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
  w.threshold.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kThreshold);
  w.inSet.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kInSet);
  w.vertexAncestors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kVertexAncestors);
  dispatchOverLevel("ds split", w, k, L);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
}

/// Compact G_{k+1} into level k + 1: scan, count (and the next dispatch size), scatter. GPU
/// times: "ds scan" (scan and count), "ds compact".
void compactLevel(DynamicSamplingWorkspace& w, const GridGeometry& grid, std::size_t next,
                  std::size_t L, StageTimer* timer) {
  const Program& count =
      gpu::program({.compute = {"dynamic_level.comp.glsl"}}, "dynamic sampling count");
  const Program& program =
      gpu::program({.compute = {"compact.comp.glsl"}}, "dynamic sampling compact");
  const std::size_t nv = grid.vertices();
  const DynamicSamplingWorkspace::Level& l = w.levels[next];
  {
    ScopedGpuTimer t(timer, "ds scan");
    scanBuffer(w.inSet, w.offsets, GLuint(nv), true, w.scanSums);
    count.use();
    glUniform1ui(count.uniform("uVertexCount"), GLuint(nv));
    glUniform1ui(count.uniform("uLevel"), GLuint(next));
    glUniform1ui(count.uniform("uCapacity"), GLuint(l.capacity));
    glUniform1ui(count.uniform("uOverflowSlot"), GLuint(overflowSlot(L)));
    glUniform1ui(count.uniform("uDispatchSlot"), GLuint(dispatchSlot(L)));
    w.inSet.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kInSet);
    w.offsets.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kOffsets);
    w.counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
    dispatch("ds count", {1, 1, 1});
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
  }
  ScopedGpuTimer t(timer, "ds compact");
  program.use();
  glUniform1ui(program.uniform("uVertexCount"), GLuint(nv));
  glUniform1ui(program.uniform("uCapacity"), GLuint(l.capacity));
  setGridUniforms(program, grid);
  glUniform1f(program.uniform("uRadius"), grid.radius());
  w.inSet.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kInSet);
  w.vertexAncestors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kVertexAncestors);
  w.offsets.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kOffsets);
  l.samples.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kNextSamples);
  l.ancestors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kNextAncestors);
  dispatch("ds compact", {groups(nv, 256), 1, 1});
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
}

/// What one level's evaluation left on the GPU, read back once the pass is done.
struct LevelReadBack {
  std::vector<GpuSamplePoint> samples;
  std::vector<GpuRadianceRecord> radiance;
  std::vector<float> errors;
};

/// A level's budgeted split decided on the host (budgetedSplit(), the CPU's function): E of the
/// level is read back, and the next level's samples and ancestors are uploaded with its count and
/// dispatch size. `points`/`anc`: the level's samples as the host holds them (level 0: the
/// initial ones; later: those uploaded here), replaced by the next level's.
BudgetLevel budgetedSplitGpu(DynamicSamplingWorkspace& w, const Scene& scene, std::size_t k,
                             std::size_t L, const std::vector<LevelGrid>& grids, double threshold,
                             long long kept, long long budget, std::vector<GpuSamplePoint>& points,
                             std::vector<std::int32_t>& anc) {
  const std::size_t n = points.size();
  std::vector<float> errors(n);
  if (n) w.levels[k].errors.read(errors.data(), n * sizeof(float));
  std::vector<Vec3> centres(n);
  std::vector<float> radii(n);
  for (std::size_t j = 0; j < n; ++j) {
    centres[j] = points[j].position;
    radii[j] = points[j].radius;
  }
  BudgetLevel bl;
  bl.decision = budgetedSplit(scene.medium.bounds, grids[k], centres, radii, anc, errors, threshold,
                              kept + (long long)n, budget, L - k);
  bl.grid = grids[k];
  bl.centres = std::move(centres);
  bl.radii = std::move(radii);
  bl.anc = anc;
  bl.errors = std::move(errors);
  const SplitDecision& d = bl.decision;
  const GridGeometry grid(scene.medium.bounds, grids[k]);
  const std::size_t m = d.vertices.size();
  DynamicSamplingWorkspace::Level& next = w.levels[k + 1];
  if (m > next.capacity)
    throw GpuError("dynamic sampling: level " + std::to_string(k + 1) + " (grid " +
                   std::to_string(grids[k].dims.x) + "^3) has " + std::to_string(m) +
                   " samples, more than the " + std::to_string(next.capacity) +
                   " the GPU holds per level (kMaxLevelSamples); use coarser levels or a "
                   "larger epsilon");
  points.resize(m);
  const float R = grid.radius();
  for (std::size_t i = 0; i < m; ++i) {
    const std::size_t v = d.vertices[i];
    const IVec3 c(int(v % std::size_t(grid.dims.x)),
                  int((v / std::size_t(grid.dims.x)) % std::size_t(grid.dims.y)),
                  int(v / (std::size_t(grid.dims.x) * std::size_t(grid.dims.y))));
    points[i] = {grid.bounds.min + (Vec3(c) + 0.5f) * grid.interval, R};
  }
  anc = d.ancestors;
  if (m) {
    glNamedBufferSubData(next.samples.id(), 0, GLsizeiptr(m * sizeof(GpuSamplePoint)),
                         points.data());
    glNamedBufferSubData(next.ancestors.id(), 0, GLsizeiptr(m * sizeof(std::int32_t)), anc.data());
  }
  const GLuint count = GLuint(m);
  glNamedBufferSubData(w.counts.id(), GLintptr((k + 1) * sizeof(GLuint)), sizeof(GLuint), &count);
  const GLuint dispatch[3] = {groups(m, 64), 1u, 1u};
  glNamedBufferSubData(w.counts.id(), GLintptr((dispatchSlot(L) + 3 * (k + 1)) * sizeof(GLuint)),
                       sizeof dispatch, dispatch);
  checkGl("dynamic sampling: budgeted split of level " + std::to_string(k));
  return bl;
}

/// S and ∇S of the top-up's children (budgetTopUp) on the GPU: uploaded into the last level's
/// buffers in chunks of its capacity and evaluated there as a final level (no probes).
void evaluateTopUpGpu(DynamicSamplingWorkspace& w, const TracingInputs& inputs,
                      const Volume& density, std::size_t lights, const TracerSteps& steps,
                      const DynamicSamplingSettings& settings, TopUp& t, StageTimer* timer) {
  const std::vector<LevelGrid> grids = levelGrids(settings);
  const std::size_t L = grids.size();
  DynamicSamplingWorkspace::Level& l = w.levels[L];
  // Two batches, as on the CPU (evaluateTopUp): with ∇S, then the voxel grid's without.
  for (const bool voxels : {false, true}) {
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < t.children.size(); ++i) {
      const std::size_t lv = std::size_t(t.children[i].level);
      if (lv >= 1 && lv <= L && grids[lv - 1].voxels == voxels) idx.push_back(i);
    }
    for (std::size_t first = 0; first < idx.size(); first += l.capacity) {
      const std::size_t m = std::min(l.capacity, idx.size() - first);
      std::vector<GpuSamplePoint> points(m);
      std::vector<std::int32_t> anc(m);
      for (std::size_t i = 0; i < m; ++i) {
        const RadianceSample& c = t.children[idx[first + i]];
        points[i] = {c.position, c.radius};
        anc[i] = t.ancestors[idx[first + i]];
      }
      glNamedBufferSubData(l.samples.id(), 0, GLsizeiptr(m * sizeof(GpuSamplePoint)),
                           points.data());
      glNamedBufferSubData(l.ancestors.id(), 0, GLsizeiptr(m * sizeof(std::int32_t)), anc.data());
      const GLuint count = GLuint(m);
      glNamedBufferSubData(w.counts.id(), GLintptr(L * sizeof(GLuint)), sizeof(GLuint), &count);
      evaluateLevel(w, inputs, density, lights, L,
                    voxels ? Evaluation::FinalNoGradient : Evaluation::Final, steps, settings,
                    timer);
      std::vector<GpuRadianceRecord> radiance(m);
      l.radiance.read(radiance.data(), m * sizeof(GpuRadianceRecord));
      for (std::size_t i = 0; i < m; ++i) unpackRadiance(radiance[i], t.children[idx[first + i]]);
    }
  }
  checkGl("dynamic sampling: top-up");
}

/// One splitting pass on the GPU. Without a budget every level is enqueued without a read-back;
/// the result is read once at the end. With one, each split level's E is read back and the
/// split decided on the host (budgetedSplitGpu), as on the CPU.
DynamicSamplingResult splitOnceGpu(const Scene& scene, const Volume& density,
                                   const TracingInputs& inputs,
                                   const std::vector<RadianceSample>& initial, TracerSteps steps,
                                   const DynamicSamplingSettings& settings, StageTimer* timer,
                                   std::vector<std::vector<float>>* errorsOut,
                                   DynamicSamplingWorkspace& w) {
  using Clock = std::chrono::steady_clock;
  const std::vector<LevelGrid> grids = levelGrids(settings);
  const std::size_t L = grids.size();
  DynamicSamplingResult result;
  std::vector<double> enqueueMs(L + 1, 0.0);
  const long long budget = sampleBudget(settings, initial.size());
  std::vector<BudgetLevel> decisions;  // the budget's split levels (empty without one)
  if (!initial.empty()) {
    prepareWorkspace(w, initial, settings);
    std::vector<GpuSamplePoint> points;  // the budget's host copy of the level's samples
    std::vector<std::int32_t> anc;
    long long kept = 0;  // samples of the coarser levels that stay
    double hostThreshold = 0.0;
    if (budget > 0)
      for (std::size_t i = 0; i < initial.size(); ++i) {
        points.push_back({initial[i].position, initial[i].radius});
        anc.push_back(std::int32_t(i));
      }
    for (std::size_t k = 0; k <= L; ++k) {
      const auto t0 = Clock::now();
      const bool final = k == L;
      evaluateLevel(w, inputs, density, scene.lights.size(), k,
                    !final                         ? Evaluation::Split
                    : k > 0 && grids[k - 1].voxels ? Evaluation::FinalNoGradient
                                                   : Evaluation::Final,
                    steps, settings, timer);
      if (!final) {
        if (k == 0) computeThreshold(w, settings, timer);
        if (budget > 0) {
          if (k == 0) {
            double thr[2] = {0.0, 0.0};
            w.threshold.read(thr, sizeof thr);
            hostThreshold = thr[1];
          }
          const long long n = (long long)points.size();
          decisions.push_back(
              budgetedSplitGpu(w, scene, k, L, grids, hostThreshold, kept, budget, points, anc));
          kept += n - decisions.back().decision.splits;
        } else {
          const GridGeometry grid(scene.medium.bounds, grids[k]);
          splitLevel(w, grid, k, L, timer);
          compactLevel(w, grid, k + 1, L, timer);
        }
      }
      checkGl("dynamic sampling: level " + std::to_string(k));
      enqueueMs[k] = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    }
  }
  // The one read-back of the pass: the counts (this waits for the GPU), then the levels.
  {  // the read-back's GPU time ends before the top-up's evaluation begins
    ScopedGpuTimer readTime(timer, "ds read-back");
    std::vector<GLuint> counts(dispatchSlot(L), 0u);
    double thr[2] = {0.0, 0.0};
    if (!initial.empty()) {
      w.counts.read(counts.data(), counts.size() * sizeof(GLuint));
      if (counts[overflowSlot(L)] > 0) {
        const std::size_t k = counts[overflowSlot(L) + 1];
        throw GpuError("dynamic sampling: level " + std::to_string(k) + " (grid " +
                       std::to_string(grids[k - 1].dims.x) + "^3) has " +
                       std::to_string(counts[overflowSlot(L)]) + " samples, more than the " +
                       std::to_string(w.levels[k].capacity) +
                       " the GPU holds per level (kMaxLevelSamples); use coarser levels or a "
                       "larger epsilon");
      }
      if (L > 0) w.threshold.read(thr, sizeof thr);
    }
    const double errorScale = settings.relative ? thr[0] : 0.0, threshold = thr[1];
    for (std::size_t k = 0; k <= L; ++k) {
      LevelStats ls;
      ls.resolution = k == 0 ? 0 : grids[k - 1].dims.x;
      ls.voxels = k > 0 && grids[k - 1].voxels;
      const std::size_t n = counts[k];
      ls.samples = (long long)n;
      ls.ms = enqueueMs[k];
      const bool final = k == L || n == 0;
      if (n > 0) {
        const DynamicSamplingWorkspace::Level& l = w.levels[k];
        LevelReadBack rb;
        rb.samples.resize(n);
        rb.radiance.resize(n);
        l.samples.read(rb.samples.data(), n * sizeof(GpuSamplePoint));
        l.radiance.read(rb.radiance.data(), n * sizeof(GpuRadianceRecord));
        std::vector<std::uint8_t> split(n, 0);
        if (!final) {
          rb.errors.resize(n);
          l.errors.read(rb.errors.data(), n * sizeof(float));
          ls.threshold = threshold;
          ls.errorScale = errorScale;
          if (k < decisions.size()) {
            split = decisions[k].decision.split;  // the budget's host decisions
            ls.capped = decisions[k].decision.capped;
            decisions[k].offset = result.samples.size();
          } else {
            // In double against the double threshold, as the CPU variant and the split pass
            // compare.
            for (std::size_t j = 0; j < n; ++j) split[j] = double(rb.errors[j]) > threshold;
          }
          for (std::size_t j = 0; j < n; ++j) {
            ls.split += split[j];
            if (!split[j]) ls.maxLeft = std::max(ls.maxLeft, rb.errors[j]);
          }
          ls.maxError = *std::max_element(rb.errors.begin(), rb.errors.end());
          ls.p90Error = quantile(rb.errors, 0.9);
        }
        // The samples that stay (all of them on the final level, and those the per-voxel
        // fallback splits), in evaluation order: the CPU's.
        const bool keepSplit = !final && grids[k].voxels;
        for (std::size_t j = 0; j < n; ++j) {
          if (split[j] && !keepSplit) continue;
          RadianceSample s;
          s.position = rb.samples[j].position;
          s.radius = rb.samples[j].radius;
          s.level = int(k);
          unpackRadiance(rb.radiance[j], s);
          result.samples.push_back(s);
        }
        if (!final && errorsOut) errorsOut->push_back(std::move(rb.errors));
      }
      result.levels.push_back(ls);
      if (n == 0) {
        for (std::size_t l = k + 1; l <= L; ++l) {
          LevelStats e;
          e.resolution = grids[l - 1].dims.x;
          e.voxels = grids[l - 1].voxels;
          result.levels.push_back(e);
        }
        break;
      }
    }
  }
  if (!decisions.empty()) {
    // The top-up, decided on the host as on the CPU; the children evaluated on the GPU.
    TopUp t = budgetTopUp(scene.medium.bounds, decisions, (long long)result.samples.size(), budget);
    if (!t.children.empty())
      evaluateTopUpGpu(w, inputs, density, scene.lights.size(), steps, settings, t, timer);
    applyTopUp(result, decisions, std::move(t));
  }
  if (!result.levels.empty()) result.levels[0].budget = budget;
  return result;
}

}  // namespace

DynamicSamplingResult dynamicSamplingGpu(const Scene& scene, const Volume& density,
                                         std::vector<RadianceSample> initial, TracerSteps steps,
                                         const DynamicSamplingSettings& settings, StageTimer* timer,
                                         std::vector<std::vector<float>>* errorsOut,
                                         const ShadowMaps* shadows,
                                         DynamicSamplingWorkspace* workspace) {
  context();
  TracingInputs inputs(scene, density, steps.delta1, shadows);
  inputs.skipEmptySpace(timer);
  DynamicSamplingWorkspace local;
  DynamicSamplingWorkspace& w = workspace ? *workspace : local;
  if (errorsOut) errorsOut->clear();
  const DynamicSamplingSettings s = forInitialSamples(settings, scene.medium.bounds, initial);
  return splitOnceGpu(scene, density, inputs, initial, steps, s, timer, errorsOut, w);
}

}  // namespace scatterlab::gpu
