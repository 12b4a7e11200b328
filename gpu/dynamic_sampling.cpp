#include "gpu/dynamic_sampling.h"

#include <algorithm>
#include <chrono>
#include <climits>

#include "core/error.h"
#include "gpu/context.h"
#include "gpu/shaders.h"
#include "gpu/stages.h"

namespace scatterlab::gpu {

namespace {

constexpr GLuint kScanBlock = 512;  // elements per workgroup of scan.comp.glsl

void setVec3(const Program& p, const char* name, const Vec3& v) {
  glUniform3f(p.uniform(name), v.x, v.y, v.z);
}
void setIVec3(const Program& p, const char* name, const IVec3& v) {
  glUniform3i(p.uniform(name), v.x, v.y, v.z);
}
GLuint groups(std::size_t n, GLuint size) {
  return GLuint((n + size - 1) / size);
}
/// A buffer of at least 4 bytes (GL refuses empty storage).
Buffer makeBuffer(std::size_t bytes, const void* data, std::string_view label) {
  if (bytes == 0) return Buffer(4, nullptr, 0, label);
  return Buffer(bytes, data, 0, label);
}

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
  const Buffer sums = makeBuffer(blocks * sizeof(GLuint), nullptr, "scan block sums");
  const Program& scan = scanProgram();
  scan.use();
  glUniform1ui(scan.uniform("uCount"), n);
  glUniform1i(scan.uniform("uFlags"), flags ? 1 : 0);
  in.bindBase(GL_SHADER_STORAGE_BUFFER, 0);
  out.bindBase(GL_SHADER_STORAGE_BUFFER, 1);
  sums.bindBase(GL_SHADER_STORAGE_BUFFER, 2);
  glDispatchCompute(blocks, 1, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  if (blocks > 1) {
    const Buffer scanned = makeBuffer(blocks * sizeof(GLuint), nullptr, "scanned block sums");
    scanBuffer(sums, scanned, blocks, false);
    const Program& add = scanAddProgram();
    add.use();
    glUniform1ui(add.uniform("uCount"), n);
    out.bindBase(GL_SHADER_STORAGE_BUFFER, 1);
    scanned.bindBase(GL_SHADER_STORAGE_BUFFER, 3);
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

float quantile(std::vector<float> v, double q) {
  if (v.empty()) return 0.0f;
  const std::size_t k = std::min(v.size() - 1, std::size_t(q * double(v.size())));
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
  return v[k];
}

}  // namespace

std::uint32_t exclusiveScanGpu(std::span<const std::uint8_t> flags,
                               std::span<std::uint32_t> offsets) {
  context();
  if (flags.size() != offsets.size()) throw GpuError("exclusiveScanGpu: size mismatch");
  const GLuint n = GLuint(flags.size());
  if (n == 0) return 0;
  const std::vector<GLuint> wide(flags.begin(), flags.end());
  const Buffer in = makeBuffer(n * sizeof(GLuint), wide.data(), "scan flags");
  const Buffer out = makeBuffer(n * sizeof(GLuint), nullptr, "scan offsets");
  scanBuffer(in, out, n, true);
  checkGl("scan");
  out.read(offsets.data(), n * sizeof(GLuint));
  return scanTotal(in, out, n);
}

DynamicSamplingResult dynamicSamplingGpu(const Scene& scene, const Volume& density,
                                         std::vector<RadianceSample> initial,
                                         DynamicSamplingGpuSteps steps,
                                         const DynamicSamplingSettings& settings, StageTimer* timer,
                                         std::vector<std::vector<float>>* errorsOut) {
  using Clock = std::chrono::steady_clock;
  context();
  const Program& errorProgram = cachedProgram("dynamic sampling error", [] {
    return computeProgram({"common.glsl", "dynamic_error.comp.glsl"}, {}, "dynamic sampling error");
  });
  const Program& splitProgram = cachedProgram("dynamic sampling split", [] {
    return computeProgram({"dynamic_split.comp.glsl"}, {}, "dynamic sampling split");
  });
  const Program& compactProgram = cachedProgram("dynamic sampling compact", [] {
    return computeProgram({"compact.comp.glsl"}, {}, "dynamic sampling compact");
  });
  DynamicSamplingResult result;
  const int np = settings.probes;
  // The CPU's probe directions: probe points of a unit sphere at the origin.
  RadianceSample unit;
  unit.position = Vec3(0.0f);
  unit.radius = 1.0f;
  Vec3 dirs[kMaxProbes];
  probePoints(unit, dirs, kMaxProbes);
  const TracingInputs inputs(scene, density, steps.delta1);
  const Box& bounds = scene.medium.bounds;
  const Vec3 densityInvCell = Vec3(1.0f) / density.cellSize();

  // Level 0 on the GPU: positions and radii, ancestors 0..n-1, τ of each root.
  std::size_t count = initial.size();
  Buffer samples, ancestors;
  {
    std::vector<float> pr;
    pr.reserve(count * 4);
    std::vector<std::int32_t> anc(count);
    for (std::size_t i = 0; i < count; ++i) {
      const RadianceSample& s = initial[i];
      pr.insert(pr.end(), {s.position.x, s.position.y, s.position.z, s.radius});
      anc[i] = std::int32_t(i);
    }
    samples =
        makeBuffer(pr.size() * sizeof(float), pr.data(), "dynamic sampling samples (level 0)");
    ancestors = makeBuffer(anc.size() * sizeof(std::int32_t), anc.data(),
                           "dynamic sampling ancestors (level 0)");
  }
  const Buffer rootTau = makeBuffer(count * sizeof(float), nullptr, "dynamic sampling root tau");

  const std::size_t nLevels = settings.levels.size();
  for (std::size_t level = 0; level <= nLevels; ++level) {
    const auto t0 = Clock::now();
    LevelStats ls;
    ls.resolution = level == 0 ? 0 : settings.levels[level - 1];
    ls.samples = (long long)count;
    const bool final = level == nLevels || count == 0;
    std::vector<float> pr(count * 4), res(count * 16), errors(count);
    std::vector<GLuint> flags(count);
    if (count > 0) {
      const Buffer results = makeBuffer(count * 16 * sizeof(float), nullptr, "dynamic sampling S");
      const Buffer errorBuf = makeBuffer(count * sizeof(float), nullptr, "dynamic sampling E");
      const Buffer flagBuf = makeBuffer(count * sizeof(GLuint), nullptr, "split flags");
      {
        ScopedGpuTimer t(timer, "ds evaluate+error");
        errorProgram.use();
        inputs.apply(errorProgram);
        glUniform1ui(errorProgram.uniform("uCount"), GLuint(count));
        glUniform1f(errorProgram.uniform("uDelta2"), steps.delta2);
        glUniform1i(errorProgram.uniform("uProbes"), np);
        glUniform3fv(errorProgram.uniform("uProbeDirs"), kMaxProbes, &dirs[0].x);
        glUniform1i(errorProgram.uniform("uTauMode"),
                    level == 0 ? 0 : (settings.perSampleTau ? 2 : 1));
        glUniform1f(errorProgram.uniform("uTauDelta1"), settings.delta1);
        glUniform1f(errorProgram.uniform("uEpsilon"), float(settings.epsilon));
        glUniform1i(errorProgram.uniform("uFinal"), final ? 1 : 0);
        setVec3(errorProgram, "uDensityInvCell", densityInvCell);
        samples.bindBase(GL_SHADER_STORAGE_BUFFER, 1);
        ancestors.bindBase(GL_SHADER_STORAGE_BUFFER, 2);
        rootTau.bindBase(GL_SHADER_STORAGE_BUFFER, 3);
        results.bindBase(GL_SHADER_STORAGE_BUFFER, 4);
        errorBuf.bindBase(GL_SHADER_STORAGE_BUFFER, 5);
        flagBuf.bindBase(GL_SHADER_STORAGE_BUFFER, 6);
        glDispatchCompute(groups(count, 64), 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
      }
      checkGl("dynamic sampling: evaluate and error");
      samples.read(pr.data(), pr.size() * sizeof(float));
      results.read(res.data(), res.size() * sizeof(float));
      errorBuf.read(errors.data(), errors.size() * sizeof(float));
      flagBuf.read(flags.data(), flags.size() * sizeof(GLuint));

      // Kept samples (all of them on the finest level), in the CPU's order.
      for (std::size_t j = 0; j < count; ++j) {
        if (!final && flags[j]) {
          ++ls.split;
          continue;
        }
        RadianceSample s;
        s.position = Vec3(pr[4 * j], pr[4 * j + 1], pr[4 * j + 2]);
        s.radius = pr[4 * j + 3];
        s.level = int(level);
        const float* q = &res[16 * j];
        s.S = Vec3(q[0], q[1], q[2]);
        for (int a = 0; a < 3; ++a) s.dS[a] = Vec3(q[4 + 4 * a], q[5 + 4 * a], q[6 + 4 * a]);
        result.samples.push_back(s);
      }
      if (!final) {
        ls.maxError = *std::max_element(errors.begin(), errors.end());
        ls.p90Error = quantile(errors, 0.9);
        if (errorsOut) errorsOut->push_back(errors);
      }

      if (!final) {
        // Grid information buffer of G_{k+1}.
        const GridInfoBuffer grid(bounds, settings.levels[level]);
        const std::size_t nv = grid.inSet.size();
        const std::vector<GLuint> zeros(nv, 0u);
        const std::vector<std::int32_t> none(nv, INT_MAX);
        const Buffer inSet = makeBuffer(nv * sizeof(GLuint), zeros.data(), "grid info: in set");
        const Buffer vertexAnc =
            makeBuffer(nv * sizeof(std::int32_t), none.data(), "grid info: ancestor");
        {
          ScopedGpuTimer t(timer, "ds split");
          splitProgram.use();
          glUniform1ui(splitProgram.uniform("uCount"), GLuint(count));
          setVec3(splitProgram, "uGridMin", grid.bounds.min);
          setVec3(splitProgram, "uGridInterval", grid.interval);
          setIVec3(splitProgram, "uGridDims", grid.dims);
          samples.bindBase(GL_SHADER_STORAGE_BUFFER, 1);
          ancestors.bindBase(GL_SHADER_STORAGE_BUFFER, 2);
          flagBuf.bindBase(GL_SHADER_STORAGE_BUFFER, 6);
          inSet.bindBase(GL_SHADER_STORAGE_BUFFER, 7);
          vertexAnc.bindBase(GL_SHADER_STORAGE_BUFFER, 8);
          glDispatchCompute(groups(count, 64), 1, 1);
          glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        }
        checkGl("dynamic sampling: split");
        const Buffer offsets = makeBuffer(nv * sizeof(GLuint), nullptr, "grid info: offsets");
        {
          ScopedGpuTimer t(timer, "ds scan");
          scanBuffer(inSet, offsets, GLuint(nv), true);
        }
        checkGl("dynamic sampling: scan");
        const std::size_t next = scanTotal(inSet, offsets, GLuint(nv));
        Buffer nextSamples =
            makeBuffer(next * 4 * sizeof(float), nullptr,
                       "dynamic sampling samples (level " + std::to_string(level + 1) + ")");
        Buffer nextAnc =
            makeBuffer(next * sizeof(std::int32_t), nullptr,
                       "dynamic sampling ancestors (level " + std::to_string(level + 1) + ")");
        {
          ScopedGpuTimer t(timer, "ds compact");
          compactProgram.use();
          glUniform1ui(compactProgram.uniform("uVertexCount"), GLuint(nv));
          setVec3(compactProgram, "uGridMin", grid.bounds.min);
          setVec3(compactProgram, "uGridInterval", grid.interval);
          setIVec3(compactProgram, "uGridDims", grid.dims);
          glUniform1f(compactProgram.uniform("uRadius"), grid.radius());
          inSet.bindBase(GL_SHADER_STORAGE_BUFFER, 7);
          vertexAnc.bindBase(GL_SHADER_STORAGE_BUFFER, 8);
          offsets.bindBase(GL_SHADER_STORAGE_BUFFER, 9);
          nextSamples.bindBase(GL_SHADER_STORAGE_BUFFER, 10);
          nextAnc.bindBase(GL_SHADER_STORAGE_BUFFER, 11);
          glDispatchCompute(groups(nv, 256), 1, 1);
          glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        }
        checkGl("dynamic sampling: compact");
        samples = std::move(nextSamples);
        ancestors = std::move(nextAnc);
        count = next;
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

}  // namespace scatterlab::gpu
