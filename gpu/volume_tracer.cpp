#include "gpu/volume_tracer.h"

#include <algorithm>
#include <bit>
#include <string>
#include <vector>

#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/device_samples.h"
#include "gpu/dispatch.h"
#include "gpu/empty_space.h"
#include "gpu/records.h"
#include "gpu/shaders.h"
#include "gpu/tracing.h"

namespace scatterlab::gpu {

namespace {

/// Whether samples no spot cone reaches are left untraced (TracerVariant::reach).
bool litReach(const TracerVariant& v) {
  return v.factorLights && v.reach > 0.0f;
}

/// The evaluator's variant (not the probe pass's: probes have no sphere): with SL_LIT_REACH.
ProgramVariant tracerEvaluatorVariant(const TracerShape& shape, const TracerVariant& v) {
  return tracerProgramVariant(shape, v).define("SL_LIT_REACH", litReach(v));
}

/// The tracer's program. Lanes split the lights (a power of two, for the tree sum), rows are
/// the 7 points of S and ∇S (1 without gradients), 32 / lanes samples per workgroup: 224
/// invocations per group with gradients, one per (sample, point, light) up to 32 lights.
/// levelCount: the count is counts[uLevel] (traceLevel), not uCount.
const Program& tracerProgram(const TracerShape& shape, const TracerVariant& v,
                             const ShadowMaps* shadows, bool levelCount) {
  ProgramVariant variant = tracerEvaluatorVariant(shape, v);
  variant.define("SL_LEVEL_COUNT", levelCount);
  return gpu::program(addShadowVariant(shadows, variant), "volume tracer");
}

/// Makes `program` current with the tracing inputs, δ2, the reach, the points and the results
/// bound.
void useTracer(const Program& program, const TracingInputs& inputs, float delta2,
               const TracerVariant& v, const Buffer& points, const Buffer& results) {
  program.use();
  inputs.apply(program);
  glUniform1f(program.uniform("uDelta2"), delta2);
  if (litReach(v)) glUniform1f(program.uniform("uReach"), v.reach);
  points.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kSamples);
  results.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kRadiance);
}

}  // namespace

ProgramVariant tracerProgramVariant(const TracerShape& shape, const TracerVariant& v) {
  ProgramVariant variant{.compute = {"common.glsl", "volume_tracer.comp.glsl"}};
  variant.define("SL_LANES " + std::to_string(shape.lanes))
      .define("SL_ROWS " + std::to_string(shape.rows))
      .define("SL_SLOTS " + std::to_string(shape.slots))
      .define("SL_GRADIENTS", v.gradients)
      .define("SL_FACTOR_LIGHTS", v.factorLights)
      .define("SL_LAMP_MODEL", v.lampModel)
      .define("SL_LOG_SPACE", v.logSpace);
  addShadowRaySkip(variant);
  return variant;
}

void traceLevel(const TracingInputs& inputs, std::size_t lights, const TracerVariant& variant,
                float delta2, const Buffer& points, const Buffer& results, const Buffer& counts,
                std::size_t level, std::size_t capacity, std::size_t firstSlot,
                std::optional<std::size_t> indirectSlot) {
  if (capacity == 0) return;
  const TracerShape shape = tracerShape(lights, variant.gradients);
  const Program& program = tracerProgram(shape, variant, inputs.shadows(), true);
  useTracer(program, inputs, delta2, variant, points, results);
  glUniform1ui(program.uniform("uLevel"), GLuint(level));
  glUniform1ui(program.uniform("uFirstSlot"),
               firstSlot == kFromZero ? 0xffffffffu : GLuint(firstSlot));
  counts.bindBase(GL_SHADER_STORAGE_BUFFER, binding::kLevelCounts);
  if (indirectSlot) {  // the level's own count, sized on the GPU
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, counts.id());
    dispatchIndirect("ds trace", GLintptr(*indirectSlot * sizeof(GLuint)));
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
  } else {  // enough workgroups for the capacity; those past the count return at once
    dispatch("ds trace",
             {std::min<GLuint>(groups(capacity, GLuint(shape.slots)), kMaxTraceGroups), 1, 1});
  }
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
}

void VolumeTracerGpu::trace(const Scene& scene, const Volume& density, const Buffer& points,
                            std::size_t count, const Buffer& results, bool gradients,
                            StageTimer* timer, const ShadowMaps* shadows) {
  context();
  if (count == 0) return;
  const TracerShape shape = tracerShape(scene.lights.size(), gradients);
  const TracerVariant variant{.gradients = gradients,
                              .factorLights = factor_,
                              .lampModel = lamp_,
                              .logSpace = log_,
                              .reach = reach_};
  const Program& program = tracerProgram(shape, variant, shadows, false);
  TracingInputs inputs(scene, density, delta1_, shadows, timer);
  inputs.skipEmptySpace(timer);
  useTracer(program, inputs, delta2_, variant, points, results);
  glUniform1ui(program.uniform("uCount"), GLuint(count));
  // Workgroups stride over the samples: at most 65535 (GL's least maximum) whatever the count.
  dispatch(kTracerPass, {std::min<GLuint>(groups(count, GLuint(shape.slots)), 65535u), 1, 1},
           timer);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
}

TracerShape tracerShape(std::size_t lights, bool gradients) {
  TracerShape s;
  // Up to 64 lanes: 64 lights with gradients are 448 invocations per workgroup, one light each
  // (with 32 lanes, each traced two in series and a 512-sample frame filled ~40 % of an H200's
  // resident threads).
  s.lanes = int(std::min<std::size_t>(64, std::bit_ceil(std::max<std::size_t>(1, lights))));
  s.rows = gradients ? 7 : 1;
  s.slots = std::max(1, 32 / s.lanes);
  return s;
}

void readRadianceRecords(const Buffer& results, std::span<RadianceSample> samples) {
  std::vector<GpuRadianceRecord> r(samples.size());
  results.read(r.data(), r.size() * sizeof(GpuRadianceRecord));
  // Without SL_GRADIENTS the shader writes ∇S = 0, so the records unpack as they are.
  for (size_t i = 0; i < samples.size(); ++i) unpackRadiance(r[i], samples[i]);
}

void VolumeTracerGpu::evaluate(const Scene& scene, const Volume& density,
                               std::span<RadianceSample> samples, bool gradients, StageTimer* timer,
                               const ShadowMaps* shadows) {
  context();
  if (samples.empty()) return;
  DeviceSamples d;
  d.setPoints(samples);
  trace(scene, density, d.points, samples.size(), d.radiance, gradients, timer, shadows);
  readRadianceRecords(d.radiance, samples);
}

}  // namespace scatterlab::gpu
