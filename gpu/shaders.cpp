#include "gpu/shaders.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>

#include "core/error.h"
#include "core/stages.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/validate.h"

namespace scatterlab::gpu {

std::string_view shaderSource(std::string_view file) {
  for (const EmbeddedShader& s : embeddedShaders())
    if (file == s.name) return s.source;
  std::string known;
  for (const EmbeddedShader& s : embeddedShaders())
    known += (known.empty() ? "" : ", ") + std::string(s.name);
  throw GpuError("no embedded shader '" + std::string(file) + "'; embedded: " + known);
}

namespace {

/// The loop guard of a driver that caps loop iterations (loopIterationLimit()): the buffer the
/// guarded shaders report to, binding kLoopGuard (uint trips = 2, uint cut = 0 or the serial
/// of a program whose invocation was cut), and the programs' names by serial.
struct LoopGuard {
  int limit = -1;  ///< -1: not probed yet
  GLuint buffer = 0;
  std::vector<std::string> programs{""};  ///< serial 0: none
};

LoopGuard& loopGuard() {
  static auto* g = new LoopGuard();  // leaked on purpose, as the programs (see shaders.h)
  return *g;
}

// One invocation counts to uN (2^20); a driver that ends loops early stops at its cap.
constexpr const char* kLoopProbe = R"(#version 450 core
layout(local_size_x = 1) in;
layout(std430, binding = 0) buffer Count { uint count; };
uniform uint uN;
void main() {
  uint k = 0u;
  for (uint i = 0u; i < uN; ++i) k += 1u;
  count = k;
}
)";
constexpr GLuint kLoopProbeTrips = 1u << 20;

// Put before the files of every compute and fragment stage when the driver caps loops: the
// guard's buffer (uint trips = 2, cut, fetch outside) and, under validation (gpu/validate.h),
// texelFetch checked: a texel outside the texture's level records the program's serial in
// slFetchOutside. GL leaves such a fetch undefined; llvmpipe returns 0, which a shader may come
// to rely on without anyone seeing it.
std::string loopGuardPrologue(std::size_t serial, bool checkFetches) {
  std::string s =
      "layout(std430, binding = BINDING_LOOP_GUARD) buffer SlLoopGuard {\n"
      "  uint slLoopTrips;\n"
      "  uint slLoopCut;\n"
      "  uint slFetchOutside;\n"
      "};\n";
  if (!checkFetches) return s;
  const std::string record = "atomicMax(slFetchOutside, " + std::to_string(serial) + "u);";
  const auto checked = [&](const char* sampler, const char* coords) {
    return std::string("vec4 slCheckedFetch(") + sampler + " s, " + coords +
           " p, int lod) {\n"
           "  if (any(lessThan(p, " +
           coords + "(0))) || any(greaterThanEqual(p, textureSize(s, lod)))) " + record +
           "\n"
           "  return texelFetch(s, p, lod);\n"
           "}\n";
  };
  return s + checked("sampler2D", "ivec2") + checked("sampler3D", "ivec3") +
         checked("sampler2DArray", "ivec3") + "#define texelFetch slCheckedFetch\n";
}

// Appended to every compute and fragment stage when the driver caps loops: the stage's main()
// runs as slGuardedMain(), then a loop of `trips` (2, read from the buffer so that no compiler
// unrolls it) ends after one trip only if the cap was reached, and the program's serial is
// recorded. Mesa's cap is one counter per invocation shared by every loop (gallivm's
// LP_MAX_TGSI_LOOP_ITERATIONS), so this detects a cut anywhere in the invocation.
std::string loopGuardEpilogue(std::size_t serial) {
  return "#undef main\n"
         "void main() {\n"
         "  slGuardedMain();\n"
         "  uint k = 0u;\n"
         "  for (uint i = 0u; i < slLoopTrips; ++i) ++k;\n"
         "  if (k != slLoopTrips) atomicMax(slLoopCut, " +
         std::to_string(serial) + "u);\n}\n";
}

// The built-ins whose results SCATTERLAB_GPU_IMPRECISE moves (see impreciseUlps()).
constexpr const char* kImpreciseBuiltins[] = {"exp",         "exp2", "log", "log2",      "sqrt",
                                              "inversesqrt", "sin",  "cos", "normalize", "length"};

}  // namespace

// slImprecise moves a value by ±`ulps` units in the last place, the sign from a hash of its bits
// (so that errors do not all lean one way, and the same value always moves the same way); 0,
// ±1, infinities and NaN stay, as hardware gives them exactly (and values within `ulps` of 0 or
// of infinity, which the move would carry across). Each listed built-in (and pow, of
// two arguments) is then a macro around itself: a preprocessor does not expand a macro inside
// its own expansion. (An array's `.length()` would meet the `length` macro and fail to compile
// under it: no shader calls it, and the imprecise CI run would show one that did.)
std::string imprecisePrologue(int ulps) {
  std::string s =
      "float slImprecise(float v) {\n"
      "  if (v == 0.0 || abs(v) == 1.0 || isinf(v) || isnan(v)) return v;\n"
      "  uint b = floatBitsToUint(v), m = b & 0x7fffffffu;\n"
      "  if (m <= " +
      std::to_string(ulps) + "u || m >= 0x7f800000u - " + std::to_string(ulps) +
      "u) return v;\n"
      "  uint h = (b ^ (b >> 16)) * 0x45d9f3bu;\n"
      "  h ^= h >> 16;\n"
      "  return uintBitsToFloat((h & 1u) != 0u ? b + " +
      std::to_string(ulps) + "u : b - " + std::to_string(ulps) +
      "u);\n"
      "}\n"
      "vec2 slImprecise(vec2 v) { return vec2(slImprecise(v.x), slImprecise(v.y)); }\n"
      "vec3 slImprecise(vec3 v) { return vec3(slImprecise(v.xy), slImprecise(v.z)); }\n"
      "vec4 slImprecise(vec4 v) { return vec4(slImprecise(v.xyz), slImprecise(v.w)); }\n"
      // A double's built-in (cpuSqrt, common.glsl) moves by as many units of a double's last
      // place: what a GPU's double square root may be off by.
      "double slImprecise(double v) {\n"
      "  if (v == 0.0 || abs(v) == 1.0 || isinf(v) || isnan(v)) return v;\n"
      "  uvec2 b = unpackDouble2x32(v);\n"
      "  if ((b.y & 0x7ff00000u) == 0u) return v;\n"
      "  uint h = (b.x ^ b.y ^ (b.x >> 16)) * 0x45d9f3bu;\n"
      "  h ^= h >> 16;\n"
      "  uint lo = (h & 1u) != 0u ? b.x + " +
      std::to_string(ulps) + "u : b.x - " + std::to_string(ulps) +
      "u;\n"
      "  if ((h & 1u) != 0u && lo < b.x) b.y += 1u;\n"
      "  if ((h & 1u) == 0u && lo > b.x) b.y -= 1u;\n"
      "  return packDouble2x32(uvec2(lo, b.y));\n"
      "}\n"
      "#define pow(x, y) slImprecise(pow(x, y))\n";
  for (const char* f : kImpreciseBuiltins)
    s += "#define " + std::string(f) + "(x) slImprecise(" + f + "(x))\n";
  return s;
}

int impreciseUlps() {
  static const int ulps = [] {
    const char* v = std::getenv("SCATTERLAB_GPU_IMPRECISE");
    if (!v || !*v) return 0;
    char* end = nullptr;
    const long n = std::strtol(v, &end, 10);
    if (*end || n < 0 || n > 1024)
      throw GpuError("SCATTERLAB_GPU_IMPRECISE: '" + std::string(v) +
                     "' is not a number of ulps from 0 to 1024");
    return int(n);
  }();
  return ulps;
}

int loopIterationLimit() {
  LoopGuard& g = loopGuard();
  if (g.limit >= 0) return g.limit;
  context();
  const Shader cs(GL_COMPUTE_SHADER, kLoopProbe, "loop-iteration probe");
  const Program probe({&cs}, "loop-iteration probe");
  GLuint count = 0, zero = 0;
  glCreateBuffers(1, &count);
  glNamedBufferStorage(count, sizeof zero, &zero, 0);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, count);
  glUseProgram(probe.id());
  glUniform1ui(probe.uniform("uN"), kLoopProbeTrips);
  glDispatchCompute(1, 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  GLuint done = 0;
  glGetNamedBufferSubData(count, 0, sizeof done, &done);
  glDeleteBuffers(1, &count);
  glUseProgram(0);
  checkGl("loop-iteration probe");
  g.limit = done > 0 && done < kLoopProbeTrips ? int(done) : 0;
  if (g.limit > 0) {
    const GLuint init[3] = {2u, 0u, 0u};
    glCreateBuffers(1, &g.buffer);
    glNamedBufferStorage(g.buffer, sizeof init, init, GL_DYNAMIC_STORAGE_BIT);
    glObjectLabel(GL_BUFFER, g.buffer, -1, "loop guard");
    // Only atomicMax reaches it, and loopGuardCut() reads it after its own barrier.
    exemptFromValidation(g.buffer);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding::kLoopGuard, g.buffer);
  }
  return g.limit;
}

namespace {
int forcedLightDispatches = 0;  ///< setLightDispatchesForTesting
}  // namespace

void setLightDispatchesForTesting(int parts) {
  forcedLightDispatches = std::max(0, parts);
}

int lightDispatches(int lights, double steps, double perLight) {
  if (forcedLightDispatches > 0) return std::clamp(forcedLightDispatches, 1, std::max(1, lights));
  const int cap = loopIterationLimit();
  if (cap <= 0 || lights <= 1) return 1;
  const double budget = 0.5 * double(cap) - steps;
  const double perDispatch = budget > 0.0 ? budget / (steps * perLight) : 0.0;
  const double n = std::ceil(double(lights) / std::max(1.0, std::floor(perDispatch)));
  return int(std::clamp(n, 1.0, double(lights)));
}

void resetLoopGuard() {
  LoopGuard& g = loopGuard();
  if (g.limit <= 0) return;
  const GLuint zero[2] = {0u, 0u};
  glNamedBufferSubData(g.buffer, sizeof(GLuint), sizeof zero, zero);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding::kLoopGuard, g.buffer);
}

std::string loopGuardCut() {
  LoopGuard& g = loopGuard();
  if (g.limit <= 0) return "";
  GLuint cut = 0;
  // Not counted as a host wait: only drivers that cap loops (llvmpipe) have the guard.
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glGetNamedBufferSubData(g.buffer, sizeof(GLuint), sizeof cut, &cut);
  return cut > 0 && cut < g.programs.size() ? g.programs[cut] : "";
}

std::string fetchOutside() {
  LoopGuard& g = loopGuard();
  if (g.limit <= 0 || !validating()) return "";
  GLuint serial = 0;
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glGetNamedBufferSubData(g.buffer, 2 * sizeof(GLuint), sizeof serial, &serial);
  return serial > 0 && serial < g.programs.size() ? g.programs[serial] : "";
}

Shader compileShader(GLenum stage, const std::vector<std::string>& files,
                     const std::vector<std::string>& defines, std::string_view label) {
  const bool guarded =
      (stage == GL_COMPUTE_SHADER || stage == GL_FRAGMENT_SHADER) && loopIterationLimit() > 0;
  std::string src = "#version 450 core\n";
  for (const BindingDefine& b : kBindingDefines)
    src += "#define " + std::string(b.name) + " " + std::to_string(b.value) + "\n";
  for (const std::string& c : sharedConstantDefines()) src += "#define " + c + "\n";
  for (const std::string& d : defines) src += "#define " + d + "\n";
  if (const int ulps = impreciseUlps()) src += imprecisePrologue(ulps);
  // The CPU's arithmetic where an ulp decides (file index 0 in the info log's lines).
  src += "#line 1 0\n";
  src += shaderSource("cpu_arithmetic.glsl");
  src += "\n";
  if (stage == GL_COMPUTE_SHADER)  // a 1D pass's index when it spans two axes (linearDispatch)
    src +=
        "#define SL_LINEAR_GROUP (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x)\n"
        "#define SL_LINEAR_INVOCATION (SL_LINEAR_GROUP * gl_WorkGroupSize.x + "
        "gl_LocalInvocationID.x)\n";
  std::string names;
  for (size_t i = 0; i < files.size(); ++i) names += (i ? " + " : "") + files[i];
  std::size_t serial = 0;
  if (guarded) {
    LoopGuard& g = loopGuard();
    g.programs.push_back(label.empty() ? names : std::string(label));
    serial = g.programs.size() - 1;
    src += loopGuardPrologue(serial, validating());
    src += "#define main slGuardedMain\n";
  }
  for (size_t i = 0; i < files.size(); ++i) {
    src += "#line 1 " + std::to_string(i + 1) + "\n";
    src += shaderSource(files[i]);
    src += "\n";
  }
  if (guarded)
    src += "#line 1 " + std::to_string(files.size() + 1) + "\n" + loopGuardEpilogue(serial);
  if (!files.empty()) {
    names += " (log lines are 'file-index:line' with 0 = cpu_arithmetic.glsl, ";
    for (size_t i = 0; i < files.size(); ++i)
      names += (i ? ", " : "") + std::to_string(i + 1) + " = " + files[i];
    names += ")";
  }
  if (!defines.empty()) {
    names += " [defines:";
    for (const std::string& d : defines) names += " " + d;
    names += "]";
  }
  return Shader(stage, src, names);
}

Program computeProgram(const std::vector<std::string>& files,
                       const std::vector<std::string>& defines, std::string_view label) {
  const Shader cs = compileShader(GL_COMPUTE_SHADER, files, defines, label);
  return Program({&cs}, label);
}

Program graphicsProgram(const std::vector<std::string>& vertexFiles,
                        const std::vector<std::string>& fragmentFiles,
                        const std::vector<std::string>& defines, std::string_view label) {
  const Shader vs = compileShader(GL_VERTEX_SHADER, vertexFiles, defines, label);
  const Shader fs = compileShader(GL_FRAGMENT_SHADER, fragmentFiles, defines, label);
  return Program({&vs, &fs}, label);
}

std::vector<std::string> sharedConstantDefines() {
  std::vector<std::string> out;
  for (const SharedConstant& c : kSharedConstants) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g", double(c.value));  // 9 digits: a float round-trips
    std::string v = buf;
    if (v.find_first_of(".e") == std::string::npos) v += ".0";  // a float literal, not an int
    out.push_back(std::string(c.define) + " " + v);
  }
  return out;
}

ProgramVariant& ProgramVariant::prepend(const std::string& file) {
  std::vector<std::string>& files = compute.empty() ? fragment : compute;
  files.insert(files.begin(), file);
  return *this;
}

std::string ProgramVariant::key() const {
  std::string k;
  const auto add = [&](const char* what, const std::vector<std::string>& list) {
    k += what;
    for (const std::string& s : list) k += s + ";";
  };
  add("cs:", compute);
  add("|vs:", vertex);
  add("|fs:", fragment);
  add("|defines:", defines);
  return k;
}

namespace {
std::size_t built = 0;
}

const Program& program(const ProgramVariant& v, std::string_view label) {
  static auto* cache = new std::map<std::string, Program>();  // leaked on purpose, see header
  const std::string key = v.key();
  auto it = cache->find(key);
  if (it == cache->end()) {
    if (v.compute.empty() == (v.vertex.empty() || v.fragment.empty()))
      throw GpuError("program '" + std::string(label) +
                     "': a variant has compute files or vertex and fragment files");
    std::string name(label);
    if (!v.defines.empty()) {
      name += " [";
      for (std::size_t i = 0; i < v.defines.size(); ++i) name += (i ? " " : "") + v.defines[i];
      name += "]";
    }
    Program p = v.compute.empty() ? graphicsProgram(v.vertex, v.fragment, v.defines, name)
                                  : computeProgram(v.compute, v.defines, name);
    it = cache->emplace(key, std::move(p)).first;
    ++built;
  }
  return it->second;
}

std::size_t programsBuilt() {
  return built;
}

}  // namespace scatterlab::gpu
