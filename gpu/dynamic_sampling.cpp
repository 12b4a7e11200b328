#include "gpu/dynamic_sampling.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <string>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/device_samples.h"
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

/// Layout of DynamicSamplingWorkspace::counts for L split levels (uints): [0, L] the levels'
/// sample counts, [L + 1] the largest count a level asked for beyond its capacity, [L + 2] that
/// level, then three uints (x, 1, 1) per level: its evaluate/split dispatch; then the final
/// list's end, where its top-up children begin and where the fallback's children begin, the
/// budget's running kept count, count after a cut and top-up cut, the final list's overflow, the
/// cut of each split level, the samples each level keeps and the top-up children of each split
/// level; three uints per level: its evaluate pass's dispatch with tau "visible" (8 samples
/// per workgroup, dynamic_error.comp.glsl); last, three per level for its tracer pass and three
/// for its probe pass (the tracer's samples per workgroup; the probes' y: their groups); then
/// three for the tracer pass of the final list's children with ∇S, three for the voxels'.
struct CountSlots {
  std::size_t L;
  std::size_t overflow() const { return L + 1; }
  std::size_t dispatch(std::size_t k) const { return L + 3 + 3 * k; }
  std::size_t end() const { return L + 3 + 3 * (L + 1); }
  std::size_t keptEnd() const { return end() + 1; }
  std::size_t gradEnd() const { return end() + 2; }
  std::size_t kept() const { return end() + 3; }
  std::size_t budgetCount() const { return end() + 4; }
  std::size_t topCut() const { return end() + 5; }
  std::size_t finalOverflow() const { return end() + 6; }
  std::size_t cut(std::size_t k) const { return end() + 7 + k; }
  std::size_t keptOf(std::size_t k) const { return end() + 7 + L + k; }
  std::size_t childrenOf(std::size_t k) const { return end() + 8 + 2 * L + k; }
  std::size_t evaluate(std::size_t k) const { return end() + 8 + 3 * L + 3 * k; }
  std::size_t keptSamples() const { return end() + 8 + 3 * L + 3 * (L + 1); }
  std::size_t trace(std::size_t k) const { return keptSamples() + 1 + 3 * k; }
  std::size_t probes(std::size_t k) const { return keptSamples() + 1 + 3 * (L + 1) + 3 * k; }
  std::size_t childTrace(std::size_t batch) const {
    return keptSamples() + 1 + 6 * (L + 1) + 3 * batch;
  }
  std::size_t words() const { return childTrace(2); }
};

/// The most workgroups of the evaluate pass with tau "visible" (GL's least
/// GL_MAX_COMPUTE_WORK_GROUP_COUNT): level 0's dispatch, and the count pass's indirect sizes
/// (uMaxEvaluateGroups); the workgroups stride over the rest.
constexpr GLuint kMaxEvaluateGroups = 65535;

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
          .logSpace = steps.logValues(),
          .reach = steps.factorLights ? steps.reach : 0.0f};
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
    return program(ProgramVariant{.compute = {"common.glsl", "dynamic_error.comp.glsl"},
                                  .defines = {"SL_COMBINE"}}
                       .define("SL_ERROR_BIAS", settings.biasWeight > 0.0),
                   "dynamic sampling error (combine)");
  const TracerVariant space = valueSpace(steps, false);
  ProgramVariant variant;
  if (pass == ErrorPass::Probes) {
    variant = tracerProgramVariant(probeShape(lights), space);
    variant.define("SL_PROBES").define("SL_ERROR_BIAS", settings.biasWeight > 0.0);
  } else {
    variant.compute = {"common.glsl", "dynamic_error.comp.glsl"};
    variant.define(settings.visibleTau ? "SL_TAU_LANES 8" : "SL_TAU_LANES 1")
        .define("SL_FACTOR_LIGHTS", space.factorLights)
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

/// `v` with errorGroup() (dynamic_groups.glsl: sampling/dynamic_sampling.h errorBin()).
ProgramVariant withGroups(ProgramVariant v) {
  v.compute.insert(v.compute.begin(), "dynamic_groups.glsl");
  return v;
}

// dynamic_budget.comp.glsl's cut: 1024 invocations of 4 groups each.
static_assert(kErrorBins == 1024 * 4);

/// Vertices of split grid k (G_{k+1}).
std::size_t gridVertices(const std::vector<LevelGrid>& grids, std::size_t k) {
  const IVec3 d = grids[k].dims;
  return std::size_t(d.x) * std::size_t(d.y) * std::size_t(d.z);
}

/// Sizes the workspace for `n0` initial samples and `levels`, and uploads level 0 (positions,
/// radii, each sample its own ancestor) and the counts (n0, zeros; the top-up's cut: none).
/// Returns the final list's capacity: every level's capacity (and with a budget the top-up's
/// children), at most max(BudgetLimits::samples, n0) with a budget (a cut never ends above the
/// larger of the two).
/// One part of the final list (assembleFinal): level `level`'s kept samples (group 0; keepAll:
/// the final level and a level split into the fallback's voxels, where every sample stays), or
/// the top-up's children of grid `level` (group 1: with ∇S; 2: the fallback's voxels). Its
/// flags are [base, base + n) of w.inSet.
struct AssemblyPart {
  std::size_t level = 0, base = 0, n = 0;
  unsigned group = 0;
  bool keepAll = false;
};

/// The final list's parts in its order, for the capacities of `w.levels` (set first).
std::vector<AssemblyPart> assemblyParts(const DynamicSamplingWorkspace& w,
                                        const std::vector<LevelGrid>& grids, long long budget) {
  const std::size_t L = grids.size();
  std::vector<AssemblyPart> parts;
  std::size_t base = 0;
  const auto add = [&](std::size_t level, std::size_t n, unsigned group, bool keepAll) {
    parts.push_back({level, base, n, group, keepAll});
    base += n;
  };
  for (std::size_t k = 0; k <= L; ++k) add(k, w.levels[k].capacity, 0, k == L || grids[k].voxels);
  if (budget > 0)
    for (const bool voxels : {false, true})
      for (std::size_t k = 0; k < L; ++k)
        if (grids[k].voxels == voxels) add(k, gridVertices(grids, k), voxels ? 2 : 1, false);
  return parts;
}

/// The flags of every part of `parts` together.
std::size_t assemblyFlags(const std::vector<AssemblyPart>& parts) {
  return parts.empty() ? 0 : parts.back().base + parts.back().n;
}

std::size_t prepareWorkspace(DynamicSamplingWorkspace& w,
                             const std::vector<RadianceSample>& initial,
                             const DynamicSamplingSettings& settings, long long budget) {
  const std::vector<LevelGrid> grids = levelGrids(settings);
  const std::size_t L = grids.size(), n0 = initial.size();
  const CountSlots slots{L};
  if (w.levels.size() < L + 1) w.levels.resize(L + 1);
  std::size_t finalCapacity = 0;
  for (std::size_t k = 0; k <= L; ++k) {
    std::size_t cap = n0;
    if (k > 0) cap = std::min(gridVertices(grids, k - 1), w.maxLevelSamples);
    DynamicSamplingWorkspace::Level& l = w.levels[k];
    l.capacity = cap;
    finalCapacity += cap;
    ensure(l.samples, cap * sizeof(GpuSamplePoint), levelLabel("samples", k));
    ensure(l.ancestors, cap * sizeof(std::int32_t), levelLabel("ancestors", k));
    ensure(l.radiance, cap * sizeof(GpuRadianceRecord), levelLabel("S", k));
    ensure(l.errors, (k == 0 ? 2 : 1) * cap * sizeof(float), levelLabel("E", k));
    if (budget > 0 && k < L) {
      ensure(l.vertexKeys, gridVertices(grids, k) * sizeof(GLuint), levelLabel("error keys", k));
      finalCapacity += gridVertices(grids, k);  // the top-up's children
    }
  }
  // The final list: at most the budget's samples (the initial ones may be more).
  if (budget > 0)
    finalCapacity =
        std::min(finalCapacity, std::max(std::size_t(budgetLimits(settings, budget).samples), n0));
  // The grid information buffer, and the final assembly's flags and offsets over a level's
  // samples or a grid's vertices.
  std::size_t vertices = n0;
  for (std::size_t k = 0; k < L; ++k)
    vertices = std::max({vertices, gridVertices(grids, k), w.levels[k + 1].capacity});
  vertices = std::max(vertices, assemblyFlags(assemblyParts(w, grids, budget)));
  if (vertices > w.vertices) {
    ensure(w.inSet, vertices * sizeof(GLuint), "grid info: in set");
    ensure(w.vertexAncestors, vertices * sizeof(std::int32_t), "grid info: ancestor");
    ensure(w.offsets, vertices * sizeof(GLuint), "grid info: offsets");
    w.vertices = vertices;
  }
  ensure(w.threshold, 2 * sizeof(double), "dynamic sampling threshold");
  ensure(w.rootTau, n0 * sizeof(float), "dynamic sampling root tau");
  if (budget > 0)
    ensure(w.histograms, std::max<std::size_t>(L, 1) * 2 * kErrorBins * sizeof(GLuint),
           "dynamic sampling error-group histograms");
  std::size_t probed = 0;  // the largest level that is probed (all but the last)
  for (std::size_t k = 0; k < L; ++k) probed = std::max(probed, w.levels[k].capacity);
  ensure(w.probeSums,
         probed * std::size_t(probeGroups(settings.probes)) * (settings.biasWeight > 0.0 ? 2 : 1) *
             sizeof(float),
         "dynamic sampling probe sums");
  ensure(w.counts, slots.words() * sizeof(GLuint), "dynamic sampling counts");
  std::vector<GLuint> counts(slots.words(), 0u);
  counts[0] = GLuint(n0);
  counts[slots.topCut()] = GLuint(kErrorBins);
  glNamedBufferSubData(w.counts.id(), 0, GLsizeiptr(counts.size() * sizeof(GLuint)), counts.data());
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
  return finalCapacity;
}

/// One invocation per sample of level k: level 0's size is known on the host (its capacity);
/// a later level's is the dispatch size the count pass left in w.counts (no read-back).
void dispatchOverLevel(const char* pass, const DynamicSamplingWorkspace& w, std::size_t k,
                       std::size_t L) {
  if (k == 0) {
    dispatch(pass, linearDispatch(groups(w.levels[0].capacity, 64)));
    return;
  }
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, w.counts.id());
  dispatchIndirect(pass, GLintptr(CountSlots{L}.dispatch(k) * sizeof(GLuint)));
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
}

/// Evaluate level k (its count on the GPU after level 0): S and ∇S by the tracer's pass
/// (traceLevel); unless final, then (dynamic_error.comp.glsl) τ and on level 0 the
/// contributions, the probes in groups of kProbeGroup, and E_j. GPU time: "ds evaluate+error".
void evaluateLevel(DynamicSamplingWorkspace& w, const TracingInputs& inputs, const Volume& density,
                   std::size_t lights, std::size_t k, LevelEvaluation mode,
                   const TracerSteps& steps, const DynamicSamplingSettings& settings,
                   StageTimer* timer) {
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
  // After level 0 the count pass sized the tracer's and the probes' dispatches for the level's
  // own count (a level's capacity is its grid's vertices: up to 4096 workgroups that would
  // mostly return at once).
  traceLevel(inputs, lights, valueSpace(steps, mode != LevelEvaluation::FinalVoxels), steps.delta2,
             l.samples, l.radiance, w.counts, k, l.capacity, kFromZero,
             k > 0 ? std::optional<std::size_t>(CountSlots{L}.trace(k)) : std::nullopt);
  if (mode != LevelEvaluation::Split) {  // a final level has S and ∇S, and no E
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
    setVec3(program, "uDensityInvCell", Vec3(1.0f) / density.cellSize());
    l.samples.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
    l.ancestors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kAncestors);
    w.rootTau.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRootTau);
    l.radiance.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRadiance);
    l.errors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kErrors);
    w.counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
    // Workgroups of 64 / lanes samples (they stride over the samples where the device's limit
    // caps their count); after level 0 the count pass left the size (the count is known only
    // on the GPU).
    if (!settings.visibleTau) {
      dispatchOverLevel("ds evaluate", w, k, L);
    } else if (k == 0) {
      dispatch("ds evaluate", {std::min<GLuint>(groups(l.capacity, 8), kMaxEvaluateGroups), 1, 1});
    } else {
      glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, w.counts.id());
      dispatchIndirect("ds evaluate", GLintptr(CountSlots{L}.evaluate(k) * sizeof(GLuint)));
      glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
    }
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
    // Level 0: workgroups for its count, known on the host; after it the count pass's size for
    // the level's own count (at most kMaxTraceGroups along x; they stride over the samples).
    if (k == 0) {
      const TracerShape shape = probeShape(lights);
      dispatch("ds probes",
               {std::min<GLuint>(groups(l.capacity, GLuint(shape.slots)), kMaxTraceGroups),
                GLuint(groupsPerSample), 1});
    } else {
      glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, w.counts.id());
      dispatchIndirect("ds probes", GLintptr(CountSlots{L}.probes(k) * sizeof(GLuint)));
      glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
    }
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
  {  // pass 3: E_j from the groups' sums
    const Program& program = errorProgram(inputs, steps, settings, ErrorPass::Combine, lights);
    program.use();
    glUniform1ui(program.uniform("uLevel"), GLuint(k));
    glUniform1i(program.uniform("uProbes"), probes);
    glUniform1i(program.uniform("uProbeGroups"), groupsPerSample);
    if (settings.biasWeight > 0.0)
      glUniform1f(program.uniform("uBiasWeight"), float(settings.biasWeight));
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

/// dynamic_budget.comp.glsl's cut of level k (or, with topUp, the top-up's after level L = k).
void dispatchCut(DynamicSamplingWorkspace& w, std::size_t k, std::size_t L,
                 const BudgetLimits& budget, bool fallback, bool topUp) {
  const CountSlots slots{L};
  const Program& cut =
      gpu::program({.compute = {"dynamic_budget.comp.glsl"}}, "dynamic sampling budget cut");
  cut.use();
  glUniform1ui(cut.uniform("uLevel"), GLuint(k));
  glUniform1ui(cut.uniform("uSplitLevels"), GLuint(L));
  glUniform1i(cut.uniform("uTopUp"), topUp ? 1 : 0);
  glUniform1i(cut.uniform("uBudget"), GLint(std::min<long long>(budget.units, INT_MAX)));
  glUniform1i(cut.uniform("uSampleLimit"), GLint(std::min<long long>(budget.samples, INT_MAX)));
  glUniform1i(cut.uniform("uUnit"), GLint(budget.sampleUnit));
  glUniform1i(cut.uniform("uFallback"), fallback ? 1 : 0);
  glUniform1ui(cut.uniform("uKeptSlot"), GLuint(slots.kept()));
  glUniform1ui(cut.uniform("uKeptSamplesSlot"), GLuint(slots.keptSamples()));
  glUniform1ui(cut.uniform("uCountSlot"), GLuint(slots.budgetCount()));
  glUniform1ui(cut.uniform("uCutSlot"), GLuint(topUp ? slots.topCut() : slots.cut(k)));
  glUniform1ui(cut.uniform("uCutsSlot"), GLuint(slots.cut(0)));
  w.counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
  w.histograms.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kGroupHistograms);
  dispatch("ds budget cut", {1, 1, 1});
  // The split's indirect dispatch reads its size from the same buffer (another slot: the
  // validator, gpu/validate.h, sees the binding, not the slots).
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
}

/// The budget's cut of level k (budgetedSplit's error groups, on the GPU): the keys pass (each
/// candidate raises its vertices of G_{k+1} to 1 + its group, and counts itself), the vertices'
/// histogram, and the one-workgroup cut, which leaves the level's cut, the count after it and
/// the samples kept so far in w.counts. GPU time: "ds budget".
void budgetLevel(DynamicSamplingWorkspace& w, const GridGeometry& grid, std::size_t k,
                 std::size_t L, const BudgetLimits& budget, bool fallback, StageTimer* timer) {
  const std::size_t nv = grid.vertices();
  const GLuint zero = 0;
  const GLuint histBase = GLuint(k * 2 * kErrorBins);
  const DynamicSamplingWorkspace::Level& l = w.levels[k];
  ScopedGpuTimer t(timer, "ds budget");
  glClearNamedBufferSubData(l.vertexKeys.id(), GL_R32UI, 0, GLsizeiptr(nv * sizeof(GLuint)),
                            GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  glClearNamedBufferSubData(w.histograms.id(), GL_R32UI, GLintptr(histBase * sizeof(GLuint)),
                            GLsizeiptr(2 * kErrorBins * sizeof(GLuint)), GL_RED_INTEGER,
                            GL_UNSIGNED_INT, &zero);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  {
    const Program& keys = gpu::program(
        withGroups({.compute = {"dynamic_split.comp.glsl"}, .defines = {"SL_BUDGET_KEYS"}}),
        "dynamic sampling budget keys");
    keys.use();
    glUniform1ui(keys.uniform("uLevel"), GLuint(k));
    setGridUniforms(keys, grid);
    glUniform1i(keys.uniform("uCell"), grid.voxels || grid.cells ? 1 : 0);
    glUniform1i(keys.uniform("uVoxels"), grid.voxels ? 1 : 0);
    glUniform1ui(keys.uniform("uHistogramBase"), histBase);
    l.samples.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
    l.errors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kErrors);
    w.counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
    w.threshold.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kThreshold);
    l.vertexKeys.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kVertexKeys);
    w.histograms.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kGroupHistograms);
    dispatchOverLevel("ds budget keys", w, k, L);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
  {
    const Program& vertices =
        gpu::program({.compute = {"dynamic_budget.comp.glsl"}, .defines = {"SL_VERTEX_GROUPS"}},
                     "dynamic sampling budget vertices");
    vertices.use();
    glUniform1ui(vertices.uniform("uVertexCount"), GLuint(nv));
    glUniform1ui(vertices.uniform("uHistogramBase"), histBase);
    l.vertexKeys.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kVertexKeys);
    w.histograms.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kGroupHistograms);
    dispatch("ds budget vertices", linearDispatch(groups(nv, 256)));
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
  dispatchCut(w, k, L, budget, fallback, false);
}

/// The top-up's cut (budgetTopUp's, on the GPU): every split level's histograms below its cut,
/// against the budget; leaves the cut in w.counts. GPU time: "ds budget".
void budgetTopUpCut(DynamicSamplingWorkspace& w, std::size_t L, const BudgetLimits& budget,
                    bool fallback, StageTimer* timer) {
  ScopedGpuTimer t(timer, "ds budget");
  dispatchCut(w, L, L, budget, fallback, true);
}

/// Split level k into the grid information buffer of G_{k+1} (cleared first): every candidate,
/// or with a budget those of the groups at or above the level's cut. GPU time: "ds split".
void splitLevel(DynamicSamplingWorkspace& w, const GridGeometry& grid, std::size_t k, std::size_t L,
                bool budgeted, StageTimer* timer) {
  ProgramVariant variant{.compute = {"dynamic_split.comp.glsl"}};
  if (budgeted) variant = withGroups(variant.define("SL_BUDGET"));
  const Program& program = gpu::program(variant, "dynamic sampling split");
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
  if (budgeted) glUniform1ui(program.uniform("uCutSlot"), GLuint(CountSlots{L}.cut(k)));
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

/// The next level's tracer and probe passes as the count pass sizes them: samples per workgroup
/// (the tracer's slots, the same for both) and the probes' groups (0: the level is not probed).
struct IndirectShape {
  GLuint samplesPerGroup = 1, probeGroups = 0;
};

/// Compact G_{k+1} into level k + 1: scan, count (and the next level's dispatch sizes), scatter.
/// GPU times: "ds scan" (scan and count), "ds compact".
void compactLevel(DynamicSamplingWorkspace& w, const GridGeometry& grid, std::size_t next,
                  std::size_t L, const IndirectShape& shape, StageTimer* timer) {
  const Program& count =
      gpu::program({.compute = {"dynamic_level.comp.glsl"}}, "dynamic sampling count");
  const Program& program = gpu::program({.compute = {"grid_vertex.glsl", "compact.comp.glsl"}},
                                        "dynamic sampling compact");
  const std::size_t nv = grid.vertices();
  const DynamicSamplingWorkspace::Level& l = w.levels[next];
  {
    ScopedGpuTimer t(timer, "ds scan");
    scanBuffer(w.inSet, w.offsets, GLuint(nv), true, w.scanSums);
    count.use();
    glUniform1ui(count.uniform("uVertexCount"), GLuint(nv));
    glUniform1ui(count.uniform("uLevel"), GLuint(next));
    glUniform1ui(count.uniform("uCapacity"), GLuint(l.capacity));
    glUniform1ui(count.uniform("uOverflowSlot"), GLuint(CountSlots{L}.overflow()));
    glUniform1ui(count.uniform("uDispatchSlot"), GLuint(CountSlots{L}.dispatch(0)));
    glUniform1ui(count.uniform("uEvaluateSlot"), GLuint(CountSlots{L}.evaluate(0)));
    glUniform1ui(count.uniform("uMaxEvaluateGroups"), kMaxEvaluateGroups);
    glUniform1ui(count.uniform("uTraceSlot"), GLuint(CountSlots{L}.trace(0)));
    glUniform1ui(count.uniform("uProbesSlot"), GLuint(CountSlots{L}.probes(0)));
    glUniform1ui(count.uniform("uSamplesPerGroup"), shape.samplesPerGroup);
    glUniform1ui(count.uniform("uProbeGroups"), shape.probeGroups);
    glUniform1ui(count.uniform("uMaxTraceGroups"), kMaxTraceGroups);
    glUniform1ui(count.uniform("uLinearFold"), linearFold());
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
  dispatch("ds compact", linearDispatch(groups(nv, 256)));
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
}

/// The final list's destination: the buffers and their capacity.
struct FinalList {
  const Buffer& points;
  const Buffer& radiance;
  std::size_t capacity;
};

/// The copy of counts[from] into counts[to] (a one-uint GPU copy).
void copyCount(const Buffer& counts, std::size_t from, const Buffer& to, std::size_t at) {
  glCopyNamedBufferSubData(counts.id(), to.id(), GLintptr(from * sizeof(GLuint)),
                           GLintptr(at * sizeof(GLuint)), sizeof(GLuint));
}

/// The final list in the CPU's order: the samples each level keeps, level by level, then the
/// top-up's children (with ∇S, then the fallback's voxels without), their S traced in place. The
/// parts' flags lie one after the other in w.inSet (assemblyParts), one scan over all of them
/// gives every sample its slot, and one pass the parts' totals and the list's ends.
/// GPU time: "ds assemble" (the children's tracing: "ds evaluate+error").
void assembleFinal(DynamicSamplingWorkspace& w, const TracingInputs& inputs, std::size_t lights,
                   const Scene& scene, const std::vector<LevelGrid>& grids, long long budget,
                   const TracerSteps& steps, const FinalList& out, StageTimer* timer) {
  const std::size_t L = grids.size();
  const CountSlots slots{L};
  const std::vector<AssemblyPart> parts = assemblyParts(w, grids, budget);
  const Program& keepFlags = gpu::program(
      withGroups({.compute = {"dynamic_assemble.comp.glsl"}, .defines = {"SL_KEEP_FLAGS"}}),
      "ds assemble: kept samples");
  const Program& keepScatter =
      gpu::program({.compute = {"dynamic_assemble.comp.glsl"}, .defines = {"SL_KEEP_SCATTER"}},
                   "ds assemble: copy kept samples");
  const Program& childFlags =
      gpu::program({.compute = {"dynamic_assemble.comp.glsl"}, .defines = {"SL_CHILD_FLAGS"}},
                   "ds assemble: top-up children");
  const Program& childScatter =
      gpu::program({.compute = {"grid_vertex.glsl", "dynamic_assemble.comp.glsl"},
                    .defines = {"SL_CHILD_SCATTER"}},
                   "ds assemble: place top-up children");
  const Program& ends =
      gpu::program({.compute = {"dynamic_assemble.comp.glsl"}, .defines = {"SL_PART_ENDS"}},
                   "ds assemble: the parts' ends");
  const std::size_t total = assemblyFlags(parts);
  std::size_t children[2] = {0, 0};  // capacity of the two batches: with ∇S, the voxels
  {
    ScopedGpuTimer t(timer, "ds assemble");
    const auto common = [&](const Program& p, const AssemblyPart& part) {
      p.use();
      glUniform1ui(p.uniform("uCount"), GLuint(part.n));
      glUniform1ui(p.uniform("uBase"), GLuint(part.base));
      glUniform1ui(p.uniform("uCapacity"), GLuint(out.capacity));
      w.counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
      w.inSet.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kInSet);
      w.offsets.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kOffsets);
    };
    // Every part's flags, then one scan.
    for (const AssemblyPart& part : parts) {
      if (part.n == 0) continue;
      const DynamicSamplingWorkspace::Level& l = w.levels[part.level];
      if (part.group == 0) {
        common(keepFlags, part);
        glUniform1ui(keepFlags.uniform("uLevel"), GLuint(part.level));
        glUniform1i(keepFlags.uniform("uKeepAll"), part.keepAll ? 1 : 0);
        glUniform1i(keepFlags.uniform("uBudget"), budget > 0 ? 1 : 0);
        glUniform1ui(keepFlags.uniform("uCutSlot"),
                     GLuint(part.level < L ? slots.cut(part.level) : slots.topCut()));
        glUniform1ui(keepFlags.uniform("uTopCutSlot"), GLuint(slots.topCut()));
        l.errors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kErrors);
        w.threshold.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kThreshold);
      } else {
        common(childFlags, part);
        glUniform1ui(childFlags.uniform("uCutSlot"), GLuint(slots.cut(part.level)));
        glUniform1ui(childFlags.uniform("uTopCutSlot"), GLuint(slots.topCut()));
        l.vertexKeys.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kVertexKeys);
      }
      dispatch("ds assemble", linearDispatch(groups(part.n, 256)));
    }
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    if (total > 0) scanBuffer(w.inSet, w.offsets, GLuint(total), true, w.scanSums);
    // Every part's scatter.
    for (const AssemblyPart& part : parts) {
      if (part.n == 0) continue;
      const DynamicSamplingWorkspace::Level& l = w.levels[part.level];
      if (part.group == 0) {
        common(keepScatter, part);
        l.samples.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
        l.radiance.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRadiance);
        out.radiance.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kNextRadiance);
      } else {
        const GridGeometry grid(scene.medium.bounds, grids[part.level]);
        children[part.group - 1] += part.n;
        common(childScatter, part);
        setGridUniforms(childScatter, grid);
        glUniform1f(childScatter.uniform("uRadius"), grid.radius());
      }
      out.points.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kNextSamples);
      dispatch("ds assemble", linearDispatch(groups(part.n, 256)));
    }
    // The parts' totals and the list's ends.
    std::vector<GLuint> table;
    for (const AssemblyPart& part : parts)
      table.insert(table.end(), {GLuint(part.base), GLuint(part.n),
                                 GLuint(part.group == 0 ? slots.keptOf(part.level)
                                                        : slots.childrenOf(part.level)),
                                 GLuint(part.group)});
    ensure(w.parts, std::max<std::size_t>(table.size(), 4) * sizeof(GLuint),
           "dynamic sampling final list's parts");
    if (!table.empty())
      glNamedBufferSubData(w.parts.id(), 0, GLsizeiptr(table.size() * sizeof(GLuint)),
                           table.data());
    ends.use();
    glUniform1ui(ends.uniform("uParts"), GLuint(parts.size()));
    glUniform1ui(ends.uniform("uCapacity"), GLuint(out.capacity));
    glUniform1ui(ends.uniform("uKeptEndSlot"), GLuint(slots.keptEnd()));
    glUniform1ui(ends.uniform("uGradEndSlot"), GLuint(slots.gradEnd()));
    glUniform1ui(ends.uniform("uEndSlot"), GLuint(slots.end()));
    glUniform1ui(ends.uniform("uOverflowSlot"), GLuint(slots.finalOverflow()));
    glUniform1ui(ends.uniform("uChildTraceSlot"), GLuint(slots.childTrace(0)));
    glUniform1ui(ends.uniform("uSamplesPerGroup"), GLuint(tracerShape(lights, true).slots));
    glUniform1ui(ends.uniform("uMaxTraceGroups"), kMaxTraceGroups);
    w.counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
    w.inSet.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kInSet);
    w.offsets.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kOffsets);
    w.parts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kAssembleParts);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    dispatch("ds assemble end", {1, 1, 1});
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT |
                    GL_COMMAND_BARRIER_BIT);
  }
  if (children[0] == 0 && children[1] == 0) return;
  // The children's S (final samples: no probes), in place: ∇S for those of the split grids,
  // none for the fallback's voxels (as the voxel level itself).
  ScopedGpuTimer t(timer, "ds evaluate+error");
  // Their dispatches sized on the GPU for the children there are (the capacities count every
  // vertex a top-up could take).
  if (children[0] > 0)
    traceLevel(inputs, lights, valueSpace(steps, true), steps.delta2, out.points, out.radiance,
               w.counts, slots.gradEnd(), std::min(children[0], out.capacity), slots.keptEnd(),
               slots.childTrace(0));
  if (children[1] > 0)
    traceLevel(inputs, lights, valueSpace(steps, false), steps.delta2, out.points, out.radiance,
               w.counts, slots.end(), std::min(children[1], out.capacity), slots.gradEnd(),
               slots.childTrace(1));
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
}

/// One splitting pass as GPU passes (runSplitPass()'s steps), enqueued without a wait, the
/// budget's decisions included; the final list goes to `out`.
class GpuSplitPass final : public SplitPassSteps {
 public:
  struct Inputs {
    const Scene& scene;
    const Volume& density;
    const TracingInputs& tracing;
    const TracerSteps& steps;
    const DynamicSamplingSettings& settings;
    const SplitPassPlan& plan;
    StageTimer* timer;
  };
  GpuSplitPass(const Inputs& in, DynamicSamplingWorkspace& w, FinalList out,
               DeviceSamples* resident)
      : in_(in), w_(w), out_(out), resident_(resident) {}

  void evaluate(std::size_t k, LevelEvaluation e) override {
    evaluateLevel(w_, in_.tracing, in_.density, in_.scene.lights.size(), k, e, in_.steps,
                  in_.settings, in_.timer);
  }
  void threshold() override { computeThreshold(w_, in_.settings, in_.timer); }
  void split(std::size_t k) override {
    const SplitPassPlan& plan = in_.plan;
    const std::size_t L = plan.levels();
    const GridGeometry grid(in_.scene.medium.bounds, plan.grids[k]);
    if (plan.budget > 0) budgetLevel(w_, grid, k, L, plan.limits, plan.fallback(), in_.timer);
    splitLevel(w_, grid, k, L, plan.budget > 0, in_.timer);
    // The next level's passes: probed unless it is the last (levelProbes: fewer before the
    // per-voxel fallback).
    const IndirectShape next{
        .samplesPerGroup = GLuint(probeShape(in_.scene.lights.size()).slots),
        .probeGroups =
            k + 1 < L ? GLuint(probeGroups(levelProbes(in_.settings, plan.grids[k + 1]))) : 0u};
    compactLevel(w_, grid, k + 1, L, next, in_.timer);
  }
  void endLevel(std::size_t k) override { checkGl("dynamic sampling: level " + std::to_string(k)); }
  void topUp() override {
    budgetTopUpCut(w_, in_.plan.levels(), in_.plan.limits, in_.plan.fallback(), in_.timer);
  }
  void finish() override {
    assembleFinal(w_, in_.tracing, in_.scene.lights.size(), in_.scene, in_.plan.grids,
                  in_.plan.budget, in_.steps, out_, in_.timer);
    if (resident_) {
      copyCount(w_.counts, CountSlots{in_.plan.levels()}.end(), resident_->onDevice->count, 0);
      resident_->radianceCurrent = true;
    }
    checkGl("dynamic sampling: final list");
  }

 private:
  Inputs in_;
  DynamicSamplingWorkspace& w_;
  FinalList out_;
  DeviceSamples* resident_;
};

/// One splitting pass on the GPU, enqueued without a wait. Records the pass in w.pass for
/// readDynamicSamplingGpu.
void enqueueSplitPass(const Scene& scene, const Volume& density, const TracingInputs& inputs,
                      const std::vector<RadianceSample>& initial, TracerSteps steps,
                      const DynamicSamplingSettings& settings, StageTimer* timer,
                      DynamicSamplingWorkspace& w, DeviceSamples* resident) {
  const SplitPassPlan plan = splitPassPlan(settings, initial.size());
  const std::size_t L = plan.levels();
  DynamicSamplingWorkspace::Pass& pass = w.pass;
  pass = {};
  pass.settings = settings;
  pass.initial = initial.size();
  pass.budget = plan.budget;
  pass.enqueueMs.assign(L + 1, 0.0);
  if (initial.empty()) return;
  const std::size_t finalCapacity = prepareWorkspace(w, initial, settings, plan.budget);
  pass.finalCapacity = finalCapacity;
  if (resident) {
    // Per part of the list its most samples and their radius, for the bound on the gather's
    // bin entries: the initial samples, each level, and the top-up's children of each grid.
    std::vector<std::pair<std::size_t, float>> radii;
    float r0 = 0.0f;
    for (const RadianceSample& s : initial) r0 = std::max(r0, s.radius);
    radii.emplace_back(std::min(initial.size(), finalCapacity), r0);
    for (std::size_t k = 0; k < L; ++k) {
      const float R = GridGeometry(scene.medium.bounds, plan.grids[k]).radius();
      radii.emplace_back(std::min(w.levels[k + 1].capacity, finalCapacity), R);
      if (plan.budget > 0)
        radii.emplace_back(std::min(gridVertices(plan.grids, k), finalCapacity), R);
    }
    resident->reserveOnDevice(finalCapacity, std::move(radii));
    pass.finalPoints = &resident->points;
    pass.finalRadiance = &resident->radiance;
  } else {
    ensure(w.finalPoints, finalCapacity * sizeof(GpuSamplePoint), "dynamic sampling final list");
    ensure(w.finalRadiance, finalCapacity * sizeof(GpuRadianceRecord), "dynamic sampling final S");
    pass.finalPoints = &w.finalPoints;
    pass.finalRadiance = &w.finalRadiance;
  }
  GpuSplitPass gpuPass({.scene = scene,
                        .density = density,
                        .tracing = inputs,
                        .steps = steps,
                        .settings = settings,
                        .plan = plan,
                        .timer = timer},
                       w, {*pass.finalPoints, *pass.finalRadiance, finalCapacity}, resident);
  pass.enqueueMs = runSplitPass(gpuPass, plan);
}

}  // namespace

DynamicSamplingResult readDynamicSamplingGpu(const DynamicSamplingWorkspace& w, bool samples,
                                             std::vector<std::vector<float>>* errorsOut) {
  const DynamicSamplingWorkspace::Pass& pass = w.pass;
  const DynamicSamplingSettings& settings = pass.settings;
  const std::vector<LevelGrid> grids = levelGrids(settings);
  const std::size_t L = grids.size();
  const CountSlots slots{L};
  const long long budget = pass.budget;
  if (errorsOut) errorsOut->clear();
  DynamicSamplingResult result;
  std::vector<GLuint> counts(slots.words(), 0u);
  double thr[2] = {0.0, 0.0};
  if (pass.initial > 0) {
    context();
    // Two host waits in all: the counts and the threshold (waits for the pass), then the errors
    // of every split level and the final list, whose sizes the counts give.
    const BufferRange first[] = {{&w.counts, 0, counts.size() * sizeof(GLuint), counts.data()},
                                 {&w.threshold, 0, L > 0 ? sizeof thr : 0, thr}};
    readBuffers(first);
    if (counts[slots.overflow()] > 0) {
      const std::size_t k = counts[slots.overflow() + 1];
      throw GpuError("dynamic sampling: level " + std::to_string(k) + " (grid " +
                     std::to_string(grids[k - 1].dims.x) + "^3) has " +
                     std::to_string(counts[slots.overflow()]) + " samples, more than the " +
                     std::to_string(w.levels[k].capacity) +
                     " the GPU holds per level (kMaxLevelSamples); use coarser levels or a "
                     "larger epsilon");
    }
    if (counts[slots.finalOverflow()] > 0)
      throw GpuError("dynamic sampling: the final list asked for " +
                     std::to_string(counts[slots.finalOverflow()]) + " samples, more than its " +
                     std::to_string(pass.finalCapacity) + " (an internal bound; a bug)");
  }
  std::vector<std::vector<float>> levelErrors(L);
  std::vector<GpuSamplePoint> points;
  std::vector<GpuRadianceRecord> radiance;
  if (pass.initial > 0) {
    std::vector<BufferRange> second;
    for (std::size_t k = 0; k < L; ++k) {
      levelErrors[k].resize(counts[k]);
      second.push_back({&w.levels[k].errors, 0, counts[k] * sizeof(float), levelErrors[k].data()});
    }
    if (samples) {
      const std::size_t total = counts[slots.end()];
      points.resize(total);
      radiance.resize(total);
      second.push_back({pass.finalPoints, 0, total * sizeof(GpuSamplePoint), points.data()});
      second.push_back({pass.finalRadiance, 0, total * sizeof(GpuRadianceRecord), radiance.data()});
    }
    readBuffers(second);
  }
  const double errorScale = settings.relative ? thr[0] : 0.0, threshold = thr[1];
  const int topCut = budget > 0 ? int(counts[slots.topCut()]) : kErrorBins;
  for (std::size_t k = 0; k <= L; ++k) {
    LevelStats ls;
    ls.resolution = k == 0 ? 0 : grids[k - 1].dims.x;
    ls.voxels = k > 0 && grids[k - 1].voxels;
    const std::size_t n = counts[k];
    ls.samples = (long long)n + (k > 0 && budget > 0 ? counts[slots.childrenOf(k - 1)] : 0);
    ls.ms = k < pass.enqueueMs.size() ? pass.enqueueMs[k] : 0.0;
    if (k < L && n > 0) {
      std::vector<float>& errors = levelErrors[k];
      ls.threshold = threshold;
      ls.errorScale = errorScale;
      const int cut = budget > 0 ? int(counts[slots.cut(k)]) : 0;
      long long candidates = 0;
      for (std::size_t j = 0; j < n; ++j) {
        const bool candidate = double(errors[j]) > threshold;
        const int g = candidate ? errorBin(errors[j], threshold) : -1;
        candidates += candidate;
        if (candidate && g >= cut) {
          ++ls.split;
        } else if (candidate && g >= topCut) {
          ++ls.split;
          ++ls.toppedUp;
        } else {
          ls.maxLeft = std::max(ls.maxLeft, errors[j]);
        }
      }
      ls.capped = budget > 0 ? candidates - ls.split : 0;
      ls.maxError = *std::max_element(errors.begin(), errors.end());
      ls.p90Error = quantile(errors, 0.9);
      if (errorsOut) errorsOut->push_back(std::move(errors));
    }
    result.levels.push_back(ls);
  }
  if (!result.levels.empty()) result.levels[0].budget = budget;
  result.finalPerLevel.assign(L + 1, 0);
  for (std::size_t k = 0; k <= L && pass.initial > 0; ++k) {
    result.finalPerLevel[k] += counts[slots.keptOf(k)];
    if (k > 0 && budget > 0) result.finalPerLevel[k] += counts[slots.childrenOf(k - 1)];
  }
  if (samples && pass.initial > 0) {
    const std::size_t total = points.size();
    // The levels of the list's parts: each level's kept samples, then the top-up's children.
    std::vector<int> level;
    level.reserve(total);
    for (std::size_t k = 0; k <= L; ++k) level.insert(level.end(), counts[slots.keptOf(k)], int(k));
    if (budget > 0)
      for (std::size_t k = 0; k < L; ++k)
        level.insert(level.end(), counts[slots.childrenOf(k)], int(k + 1));
    result.samples.resize(total);
    for (std::size_t i = 0; i < total; ++i) {
      RadianceSample& s = result.samples[i];
      s.position = points[i].position;
      s.radius = points[i].radius;
      s.level = i < level.size() ? level[i] : int(L);
      unpackRadiance(radiance[i], s);
    }
  }
  return result;
}

DynamicSamplingResult dynamicSamplingGpu(const Scene& scene, const Volume& density,
                                         std::vector<RadianceSample> initial, TracerSteps steps,
                                         const DynamicSamplingSettings& settings, StageTimer* timer,
                                         std::vector<std::vector<float>>* errorsOut,
                                         const ShadowMaps* shadows,
                                         DynamicSamplingWorkspace* workspace,
                                         DeviceSamples* resident) {
  context();
  if (resident && !workspace)
    throw GpuError("dynamicSamplingGpu: a resident pass needs a workspace to be read from");
  TracingInputs inputs(scene, density, steps.delta1, shadows, timer);
  inputs.skipEmptySpace(timer);
  DynamicSamplingWorkspace local;
  DynamicSamplingWorkspace& w = workspace ? *workspace : local;
  if (errorsOut) errorsOut->clear();
  const DynamicSamplingSettings s = forInitialSamples(settings, scene.medium.bounds, initial);
  enqueueSplitPass(scene, density, inputs, initial, steps, s, timer, w, resident);
  if (resident) return {};
  ScopedGpuTimer readTime(timer, "ds read-back");
  return readDynamicSamplingGpu(w, true, errorsOut);
}

}  // namespace scatterlab::gpu
