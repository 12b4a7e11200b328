#include "gpu/dynamic_sampling.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <string>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/shaders.h"

namespace scatterlab::gpu {

namespace {

constexpr GLuint kScanBlock = 512;  // elements per workgroup of scan.comp.glsl

const Program& scanProgram() {
  return cachedProgram("scan (block)",
                       [] { return computeProgram({"scan.comp.glsl"}, {}, "scan (block)"); });
}
const Program& scanAddProgram() {
  return cachedProgram("scan (add block sums)", [] {
    return computeProgram({"scan.comp.glsl"}, {"SL_SCAN_ADD"}, "scan (add block sums)");
  });
}

/// Exclusive scan of n uints of `in` into `out` (flags: count non-zero as one): block scans,
/// then the block sums scanned recursively and added back.
void scanBuffer(const Buffer& in, const Buffer& out, GLuint n, bool flags) {
  if (n == 0) return;
  const GLuint blocks = groups(n, kScanBlock);
  const Buffer sums(blocks * sizeof(GLuint), nullptr, 0, "scan block sums");
  const Program& scan = scanProgram();
  scan.use();
  glUniform1ui(scan.uniform("uCount"), n);
  glUniform1i(scan.uniform("uFlags"), flags ? 1 : 0);
  in.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kScanIn);
  out.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kScanOut);
  sums.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kScanBlockSums);
  glDispatchCompute(blocks, 1, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  if (blocks > 1) {
    const Buffer scanned(blocks * sizeof(GLuint), nullptr, 0, "scanned block sums");
    scanBuffer(sums, scanned, blocks, false);
    const Program& add = scanAddProgram();
    add.use();
    glUniform1ui(add.uniform("uCount"), n);
    out.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kScanOut);
    scanned.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kScanScannedSums);
    glDispatchCompute(blocks, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
}

/// Total of an exclusive scan of flags: last offset + last flag (two small reads).
std::uint32_t scanTotal(const Buffer& flags, const Buffer& offsets, GLuint n) {
  if (n == 0) return 0;
  GLuint last = 0, flag = 0;
  offsets.read(&last, sizeof last, std::size_t(n - 1) * sizeof(GLuint));
  flags.read(&flag, sizeof flag, std::size_t(n - 1) * sizeof(GLuint));
  return last + (flag != 0 ? 1u : 0u);
}

/// The grid of G_{k+1} as split and compact read it (GridInfoBuffer::vertex's convention).
void setGridUniforms(const Program& p, const GridInfoBuffer& grid) {
  setVec3(p, "uGridMin", grid.bounds.min);
  setVec3(p, "uGridInterval", grid.interval);
  setIVec3(p, "uGridDims", grid.dims);
}

std::string levelLabel(const char* what, std::size_t level) {
  return std::string("dynamic sampling ") + what + " (level " + std::to_string(level) + ")";
}

/// Level 0 on the GPU: the initial positions and radii, each sample its own ancestor.
DynamicLevelGpu uploadInitialLevel(const std::vector<RadianceSample>& initial) {
  DynamicLevelGpu l;
  l.count = initial.size();
  std::vector<GpuSamplePoint> points;
  points.reserve(l.count);
  std::vector<std::int32_t> anc(l.count);
  for (std::size_t i = 0; i < l.count; ++i) {
    points.push_back({initial[i].position, initial[i].radius});
    anc[i] = std::int32_t(i);
  }
  l.samples =
      Buffer(points.size() * sizeof(GpuSamplePoint), points.data(), 0, levelLabel("samples", 0));
  l.ancestors =
      Buffer(anc.size() * sizeof(std::int32_t), anc.data(), 0, levelLabel("ancestors", 0));
  return l;
}

/// Appends the samples of `eval` that stay (all of them on the final level) to `out`, in
/// evaluation order: the CPU's order.
void appendKept(const LevelEvaluationGpu& eval, std::size_t level, bool final,
                std::vector<RadianceSample>& out) {
  for (std::size_t j = 0; j < eval.samples.size(); ++j) {
    if (!final && eval.splitFlags[j]) continue;
    RadianceSample s;
    s.position = eval.samples[j].position;
    s.radius = eval.samples[j].radius;
    s.level = int(level);
    unpackRadiance(eval.radiance[j], s);
    out.push_back(s);
  }
}

}  // namespace

std::uint32_t exclusiveScanGpu(std::span<const std::uint8_t> flags,
                               std::span<std::uint32_t> offsets) {
  context();
  if (flags.size() != offsets.size()) throw GpuError("exclusiveScanGpu: size mismatch");
  const GLuint n = GLuint(flags.size());
  if (n == 0) return 0;
  const std::vector<GLuint> wide(flags.begin(), flags.end());
  const Buffer in(n * sizeof(GLuint), wide.data(), 0, "scan flags");
  const Buffer out(n * sizeof(GLuint), nullptr, 0, "scan offsets");
  scanBuffer(in, out, n, true);
  checkGl("scan");
  out.read(offsets.data(), n * sizeof(GLuint));
  return scanTotal(in, out, n);
}

LevelEvaluationGpu evaluateLevelGpu(const TracingInputs& inputs, const Volume& density,
                                    const DynamicLevelGpu& level, const Buffer& rootTau, bool final,
                                    const DynamicSamplingGpuSteps& steps,
                                    const DynamicSamplingSettings& settings, StageTimer* timer) {
  context();
  std::string key = "dynamic sampling error";
  std::vector<std::string> defines;
  if (steps.factorLights) {
    defines.push_back("SL_FACTOR_LIGHTS");
    key += " V";
  }
  if (steps.factorLights && steps.logSpace) {
    defines.push_back("SL_LOG_SPACE");
    key += " ln";
  }
  if (settings.space.bounds) {
    defines.push_back("SL_BOUNDED");
    key += " bounded";
  }
  std::vector<std::string> files = {"common.glsl", "dynamic_error.comp.glsl"};
  addShadowVariant(inputs.shadows(), key, files, defines);
  const Program& program = cachedProgram(key, [&] { return computeProgram(files, defines, key); });
  const std::size_t count = level.count;
  LevelEvaluationGpu e;
  e.samples.resize(count);
  e.radiance.resize(count);
  e.errors.resize(count);
  e.splitFlags.resize(count);
  if (count == 0) return e;
  const bool root = level.level == 0;
  const Vec3* dirs = probeOffsets();  // the CPU's probe offsets of a unit sphere
  const Buffer results(count * sizeof(GpuRadianceRecord), nullptr, 0, "dynamic sampling S");
  // E per sample, then (level 0) the contributions R³·mean|S|·D·τ.
  const Buffer errors((root ? 2 : 1) * count * sizeof(float), nullptr, 0, "dynamic sampling E");
  {
    ScopedGpuTimer t(timer, "ds evaluate+error");
    program.use();
    inputs.apply(program);
    glUniform1ui(program.uniform("uCount"), GLuint(count));
    glUniform1f(program.uniform("uDelta2"), steps.delta2);
    glUniform1i(program.uniform("uProbes"), settings.probes);
    glUniform3fv(program.uniform("uProbeDirs"), kMaxProbes, &dirs[0].x);
    glUniform1i(program.uniform("uTauMode"),
                level.level == 0 ? 0 : (settings.perSampleTau ? 2 : 1));
    glUniform1f(program.uniform("uTauDelta1"), settings.delta1);
    glUniform1i(program.uniform("uFinal"), final ? 1 : 0);
    if (settings.space.bounds)
      glUniform2f(program.uniform("uTaylorBounds"), settings.space.bounds->lo,
                  settings.space.bounds->hi);
    setVec3(program, "uDensityInvCell", Vec3(1.0f) / density.cellSize());
    level.samples.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
    level.ancestors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kAncestors);
    rootTau.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRootTau);
    results.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRadiance);
    errors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kErrors);
    glDispatchCompute(groups(count, 64), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  }
  checkGl("dynamic sampling: evaluate and error");
  level.samples.read(e.samples.data(), count * sizeof(GpuSamplePoint));
  results.read(e.radiance.data(), count * sizeof(GpuRadianceRecord));
  errors.read(e.errors.data(), count * sizeof(float));
  if (root && !final) {
    e.contributions.resize(count);
    errors.read(e.contributions.data(), count * sizeof(float), count * sizeof(float));
  }
  return e;
}

void setSplitFlags(LevelEvaluationGpu& eval, double threshold) {
  context();
  const std::size_t n = eval.errors.size();
  eval.splitFlags.assign(n, 0u);
  // In double against the double threshold, as the CPU variant compares.
  for (std::size_t j = 0; j < n; ++j) eval.splitFlags[j] = double(eval.errors[j]) > threshold;
  eval.flags = Buffer(std::max<std::size_t>(n, 1) * sizeof(GLuint),
                      n ? eval.splitFlags.data() : nullptr, 0, "split flags");
}

GridInfoGpu splitLevelGpu(const DynamicLevelGpu& level, const LevelEvaluationGpu& eval,
                          const Box& bounds, int resolution, LevelStats& stats, StageTimer* timer) {
  context();
  const Program& program = cachedProgram("dynamic sampling split", [] {
    return computeProgram({"dynamic_split.comp.glsl"}, {}, "dynamic sampling split");
  });
  for (std::uint32_t f : eval.splitFlags) stats.split += f != 0 ? 1 : 0;
  if (!eval.errors.empty()) {
    stats.maxError = *std::max_element(eval.errors.begin(), eval.errors.end());
    stats.p90Error = quantile(eval.errors, 0.9);
  }
  GridInfoGpu g{GridInfoBuffer(bounds, resolution), Buffer(), Buffer()};
  const std::size_t nv = g.grid.inSet.size();
  const std::vector<GLuint> zeros(nv, 0u);
  const std::vector<std::int32_t> none(nv, INT_MAX);
  g.inSet = Buffer(nv * sizeof(GLuint), zeros.data(), 0, "grid info: in set");
  g.vertexAncestors = Buffer(nv * sizeof(std::int32_t), none.data(), 0, "grid info: ancestor");
  if (level.count == 0) return g;
  {
    ScopedGpuTimer t(timer, "ds split");
    program.use();
    glUniform1ui(program.uniform("uCount"), GLuint(level.count));
    setGridUniforms(program, g.grid);
    level.samples.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
    level.ancestors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kAncestors);
    eval.flags.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSplitFlags);
    g.inSet.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kInSet);
    g.vertexAncestors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kVertexAncestors);
    glDispatchCompute(groups(level.count, 64), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
  checkGl("dynamic sampling: split");
  return g;
}

DynamicLevelGpu compactLevelGpu(const GridInfoGpu& grid, std::size_t level, StageTimer* timer) {
  context();
  const Program& program = cachedProgram("dynamic sampling compact", [] {
    return computeProgram({"compact.comp.glsl"}, {}, "dynamic sampling compact");
  });
  const std::size_t nv = grid.grid.inSet.size();
  const Buffer offsets(nv * sizeof(GLuint), nullptr, 0, "grid info: offsets");
  {
    ScopedGpuTimer t(timer, "ds scan");
    scanBuffer(grid.inSet, offsets, GLuint(nv), true);
  }
  checkGl("dynamic sampling: scan");
  DynamicLevelGpu next;
  next.level = level;
  next.count = scanTotal(grid.inSet, offsets, GLuint(nv));
  next.samples =
      Buffer(next.count * sizeof(GpuSamplePoint), nullptr, 0, levelLabel("samples", level));
  next.ancestors =
      Buffer(next.count * sizeof(std::int32_t), nullptr, 0, levelLabel("ancestors", level));
  {
    ScopedGpuTimer t(timer, "ds compact");
    program.use();
    glUniform1ui(program.uniform("uVertexCount"), GLuint(nv));
    setGridUniforms(program, grid.grid);
    glUniform1f(program.uniform("uRadius"), grid.grid.radius());
    grid.inSet.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kInSet);
    grid.vertexAncestors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kVertexAncestors);
    offsets.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kOffsets);
    next.samples.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kNextSamples);
    next.ancestors.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kNextAncestors);
    glDispatchCompute(groups(nv, 256), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  }
  checkGl("dynamic sampling: compact");
  return next;
}

namespace {

/// One splitting pass on the GPU (no budget): dynamicSamplingGpu() without max_samples.
DynamicSamplingResult splitOnceGpu(const Scene& scene, const Volume& density,
                                   const TracingInputs& inputs,
                                   const std::vector<RadianceSample>& initial,
                                   DynamicSamplingGpuSteps steps,
                                   const DynamicSamplingSettings& settings, StageTimer* timer,
                                   std::vector<std::vector<float>>* errorsOut) {
  using Clock = std::chrono::steady_clock;
  DynamicSamplingResult result;
  DynamicLevelGpu current = uploadInitialLevel(initial);
  const Buffer rootTau(std::max<std::size_t>(current.count, 1) * sizeof(float), nullptr, 0,
                       "dynamic sampling root tau");
  double threshold = settings.epsilon, errorScale = 0.0;  // set on level 0

  const std::size_t nLevels = settings.levels.size();
  for (std::size_t level = 0; level <= nLevels; ++level) {
    const auto t0 = Clock::now();
    LevelStats ls;
    ls.resolution = level == 0 ? 0 : settings.levels[level - 1];
    ls.samples = (long long)current.count;
    const bool final = level == nLevels || current.count == 0;
    if (current.count > 0) {
      LevelEvaluationGpu eval =
          evaluateLevelGpu(inputs, density, current, rootTau, final, steps, settings, timer);
      if (!final) {
        if (level == 0) {
          errorScale = settings.relative ? relativeErrorScale(eval.contributions) : 0.0;
          threshold = settings.relative ? settings.epsilon * errorScale : settings.epsilon;
        }
        ls.threshold = threshold;
        ls.errorScale = errorScale;
        setSplitFlags(eval, threshold);
      }
      appendKept(eval, level, final, result.samples);
      if (!final) {
        if (errorsOut) errorsOut->push_back(eval.errors);
        const GridInfoGpu grid =
            splitLevelGpu(current, eval, scene.medium.bounds, settings.levels[level], ls, timer);
        current = compactLevelGpu(grid, level + 1, timer);
      }
    }
    ls.ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    result.levels.push_back(ls);
    if (ls.samples == 0) {
      for (std::size_t l = level + 1; l <= nLevels; ++l)
        result.levels.push_back(LevelStats{settings.levels[l - 1]});
      break;
    }
  }
  return result;
}

}  // namespace

DynamicSamplingResult dynamicSamplingGpu(const Scene& scene, const Volume& density,
                                         std::vector<RadianceSample> initial,
                                         DynamicSamplingGpuSteps steps,
                                         const DynamicSamplingSettings& settings, StageTimer* timer,
                                         std::vector<std::vector<float>>* errorsOut,
                                         const ShadowMaps* shadows) {
  context();
  const TracingInputs inputs(scene, density, steps.delta1, shadows);
  return withSampleBudget(settings, [&](const DynamicSamplingSettings& s) {
    if (errorsOut) errorsOut->clear();  // the errors of the pass returned
    return splitOnceGpu(scene, density, inputs, initial, steps, s, timer, errorsOut);
  });
}

}  // namespace scatterlab::gpu
