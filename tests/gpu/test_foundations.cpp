/// GL foundations: context, RAII wrappers, embedded shaders and their failure paths.

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>
#include <regex>
#include <set>

#include "core/camera.h"
#include "core/math.h"
#include "core/stages.h"
#include "gpu/dispatch.h"
#include "gpu/gl.h"
#include "gpu/shaders.h"
#include "gpu_support.h"

namespace scatterlab::testing {
namespace {

TEST(GpuContext, ReportsAnOpenGl45Device) {
  SCATTERLAB_REQUIRE_GPU();
  const gpu::DeviceInfo& info = gpu::context().info();
  EXPECT_FALSE(info.renderer.empty());
  EXPECT_FALSE(info.vendor.empty());
  EXPECT_TRUE(info.platform == "device" || info.platform == "surfaceless") << info.platform;
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  EXPECT_GE(major * 10 + minor, 45) << info.version;
  GLint profile = 0;
  glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
  EXPECT_TRUE(profile & GL_CONTEXT_CORE_PROFILE_BIT);
  std::printf("GPU test device: %s / %s / %s (%s platform)\n", info.vendor.c_str(),
              info.renderer.c_str(), info.version.c_str(), info.platform.c_str());
}

TEST(GpuWrappers, MoveAssignSwapsAndMoveConstructEmpties) {
  SCATTERLAB_REQUIRE_GPU();
  gpu::Buffer a(16, nullptr, 0, "a"), b(16, nullptr, 0, "b");
  const GLuint ida = a.id(), idb = b.id();
  ASSERT_NE(ida, 0u);
  a = std::move(b);  // swap: b now owns a's old name and deletes it when it dies
  EXPECT_EQ(a.id(), idb);
  EXPECT_EQ(b.id(), ida);
  gpu::Buffer c(std::move(a));
  EXPECT_EQ(c.id(), idb);
  EXPECT_EQ(a.id(), 0u);
  { gpu::Buffer dying(std::move(b)); }
  EXPECT_FALSE(glIsBuffer(ida));
  EXPECT_TRUE(glIsBuffer(idb));
  gpu::checkGl("wrapper test");
}

/// The stage of an embedded file from its name (x.comp.glsl, x.vert.glsl, x.frag.glsl), or 0
/// for a library file that other files are compiled with (common.glsl).
GLenum stageOf(const std::string& name) {
  for (const auto& [suffix, stage] :
       {std::pair{".comp.glsl", GL_COMPUTE_SHADER}, std::pair{".vert.glsl", GL_VERTEX_SHADER},
        std::pair{".frag.glsl", GL_FRAGMENT_SHADER}})
    if (name.ends_with(suffix)) return stage;
  return 0;
}

/// The SL_* variant macros a source tests (#ifdef, #ifndef, defined(...)).
std::set<std::string> variantsOf(const std::string& source) {
  static const std::regex re(R"((?:#\s*ifn?def\s+|defined\s*\(\s*)(SL_\w+))");
  // A size the host sets, with a default for a lone compile ("#ifndef SL_LANES" then
  // "#define SL_LANES 1"): not a switch to try on its own.
  static const std::regex size(R"(#\s*ifndef\s+(SL_\w+)[^\n]*\n\s*#\s*define\s+\1\s+\S)");
  std::set<std::string> out, sizes;
  for (auto it = std::sregex_iterator(source.begin(), source.end(), size);
       it != std::sregex_iterator(); ++it)
    sizes.insert((*it)[1].str());
  for (auto it = std::sregex_iterator(source.begin(), source.end(), re);
       it != std::sregex_iterator(); ++it)
    if (!sizes.count((*it)[1].str())) out.insert((*it)[1].str());
  return out;
}

TEST(GpuShaders, EveryEmbeddedFileIsPresent) {
  // No context needed: the table is compiled into the library.
  const auto& table = gpu::embeddedShaders();
  EXPECT_FALSE(table.empty());
  std::set<std::string> names;
  for (const gpu::EmbeddedShader& s : table) {
    EXPECT_TRUE(names.insert(s.name).second) << "twice: " << s.name;
    EXPECT_FALSE(std::string_view(s.source).empty()) << s.name;
    EXPECT_EQ(gpu::shaderSource(s.name), std::string_view(s.source)) << s.name;
  }
  EXPECT_THROW(gpu::shaderSource("nope.glsl"), GpuError);
}

/// Every shader of the embedded table, in every variant it tests, compiles (and a compute
/// shader links), so a new file or #ifdef SL_* is covered without editing this test. A stage
/// file that does not compile alone is compiled after a library file (what the stages do with
/// common.glsl), after two or three of them (screen_common.glsl builds on common.glsl;
/// common.glsl's SL_SKIP_SHADOWS on block_walk.glsl), or after all of them; it must compile one
/// way or another.
TEST(GpuShaders, EveryEmbeddedShaderCompiles) {
  SCATTERLAB_REQUIRE_GPU();
  std::vector<std::string> libraries;
  for (const gpu::EmbeddedShader& s : gpu::embeddedShaders())
    if (!stageOf(s.name) && std::string_view(s.name) != "cpu_arithmetic.glsl")  // a prelude
      libraries.push_back(s.name);
  ASSERT_FALSE(libraries.empty());
  int compiled = 0, stageFiles = 0;
  for (const gpu::EmbeddedShader& s : gpu::embeddedShaders()) {
    const GLenum stage = stageOf(s.name);
    if (!stage) continue;
    ++stageFiles;
    std::vector<std::vector<std::string>> fileSets = {{s.name}};
    for (const std::string& lib : libraries) fileSets.push_back({lib, s.name});
    // Every library together (common.glsl with SL_OBJECTS needs shadow.glsl).
    fileSets.push_back(libraries);
    fileSets.back().push_back(s.name);
    // A library may build on another (screen_common.glsl on common.glsl).
    for (const std::string& a : libraries)
      for (const std::string& b : libraries)
        if (a != b) fileSets.push_back({a, b, s.name});
    // Or on two (common.glsl with SL_SKIP_SHADOWS after block_walk.glsl, with shadow.glsl).
    for (const std::string& a : libraries)
      for (const std::string& b : libraries)
        for (const std::string& c : libraries)
          if (a != b && a != c && b != c) fileSets.push_back({a, b, c, s.name});
    std::string log;
    bool ok = false;
    for (const auto& files : fileSets) {
      std::set<std::string> variants;
      for (const std::string& f : files)
        variants.merge(variantsOf(std::string(gpu::shaderSource(f))));
      try {
        std::vector<std::vector<std::string>> defineSets = {{}};
        for (const std::string& v : variants) defineSets.push_back({v});
        for (const auto& defines : defineSets) {
          if (stage == GL_COMPUTE_SHADER)
            gpu::computeProgram(files, defines, s.name);
          else
            gpu::compileShader(stage, files, defines);
          ++compiled;
        }
        ok = true;
        break;
      } catch (const GpuError& e) {
        log += std::string(e.what()) + "\n";
      }
    }
    EXPECT_TRUE(ok) << s.name << " compiles neither alone nor after a library file:\n" << log;
  }
  EXPECT_GT(compiled, stageFiles) << "no SL_* variant found: is variantsOf broken?";
  std::printf("compiled %d shader variants from the embedded table\n", compiled);
  gpu::checkGl("compiling every embedded shader");
}

TEST(GpuShaders, CompileErrorNamesTheFileAndQuotesTheLog) {
  SCATTERLAB_REQUIRE_GPU();
  try {
    gpu::Shader s(GL_FRAGMENT_SHADER, "#version 450 core\nvoid main() { undeclared = 1; }\n",
                  "broken.frag.glsl");
    FAIL() << "expected GpuError";
  } catch (const GpuError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("broken.frag.glsl"), std::string::npos) << m;
    EXPECT_NE(m.find("undeclared"), std::string::npos) << m;
  }
  // An embedded file compiled without the file it needs: the error names it.
  try {
    gpu::computeProgram({"volume_tracer.comp.glsl"}, {}, "incomplete");
    FAIL() << "expected GpuError";
  } catch (const GpuError& e) {
    EXPECT_NE(std::string(e.what()).find("volume_tracer.comp.glsl"), std::string::npos) << e.what();
  }
  // A bad variant #define.
  EXPECT_THROW(gpu::computeProgram({"common.glsl", "volume_tracer.comp.glsl"}, {"kInvFourPi )"},
                                   "bad define"),
               GpuError);
  glGetError();  // compile failures are not GL errors, but leave the queue clean
}

TEST(GpuPassLayer, AMisspeltUniformIsAnErrorAndARemovedOneIsIgnored) {
  SCATTERLAB_REQUIRE_GPU();
  // The gather declares uTaylorBounds only under SL_BOUNDED (removed otherwise) and never
  // declares uTaylorBound. A define no source reads makes it a program of this test's own, built
  // under this label (a program keeps the label it was first built under: in one process with
  // the other tests the plain gather is 'radiance gather').
  const gpu::Program& p =
      gpu::program({.compute = {"radiance_gather.comp.glsl"}, .defines = {"SL_PASS_LAYER_TEST"}},
                   "pass layer test");
  EXPECT_GE(p.uniform("uGridDims"), 0);
  EXPECT_EQ(p.uniform("uTaylorBounds"), -1);
  try {
    (void)p.uniform("uGridDim");
    FAIL() << "expected GpuError";
  } catch (const GpuError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("uGridDim'"), std::string::npos) << m;
    EXPECT_NE(m.find("pass layer test"), std::string::npos) << m;
  }
  // Declarations are read from the sources: layout, precision, arrays; not uniform blocks.
  EXPECT_EQ(gpu::declaredUniforms("layout(binding = 0) uniform sampler3D uDensity;\n"
                                  "uniform highp vec3 uDirs[40];\nuniform Block { int x; };\n"
                                  "// not a uniform: uniformity\nuniform float uA = 1.0;"),
            (std::vector<std::string>{"uDensity", "uDirs", "uA"}));
}

TEST(GpuPassLayer, AProgramIsItsFilesAndDefines) {
  SCATTERLAB_REQUIRE_GPU();
  const gpu::ProgramVariant a{.compute = {"scan.comp.glsl"}, .defines = {"SL_SCAN_ADD"}};
  const gpu::Program& p1 = gpu::program(a, "one label");
  const std::size_t built = gpu::programsBuilt();
  // The same files and defines under another label: the same program, nothing built.
  EXPECT_EQ(&gpu::program(a, "another label"), &p1);
  EXPECT_EQ(gpu::programsBuilt(), built);
  // Another define: another program.
  gpu::ProgramVariant b = a;
  b.defines.clear();
  EXPECT_NE(&gpu::program(b, "one label"), &p1);
  EXPECT_NE(a.key(), b.key());
}

/// What one invocation of a compute shader writes to `count` floats v[] at binding 0: the text
/// is "#version 450 core", `head` (#defines, functions), the block, then main() around `body`.
std::vector<float> oneInvocationFloats(const std::string& head, const std::string& body,
                                       std::size_t count, const std::string& label) {
  const std::string src = "#version 450 core\n" + head +
                          "layout(local_size_x = 1) in;\n"
                          "layout(std430, binding = 0) buffer Out { float v[]; };\n"
                          "void main() {\n" +
                          body + "}\n";
  const gpu::Shader cs(GL_COMPUTE_SHADER, src, label);
  const gpu::Program p({&cs}, label);
  const gpu::Buffer out(count * sizeof(float), nullptr, 0, label);
  p.use();
  out.bindBase(GL_SHADER_STORAGE_BUFFER, 0);
  gpu::dispatch(label, {1, 1, 1});
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  std::vector<float> got(count);
  out.read(got.data(), got.size() * sizeof(float));
  return got;
}

TEST(GpuPassLayer, SharedConstantsReachTheShadersBitForBit) {
  SCATTERLAB_REQUIRE_GPU();
  // Each constant of kSharedConstants written by a shader that sees only the injected #define
  // reads back as the C++ float exactly (the Eq. 4 clamp once drifted: 1e-9 on the CPU, 1e-6
  // in the splat shaders).
  std::string head, body;
  for (const std::string& d : gpu::sharedConstantDefines()) head += "#define " + d + "\n";
  int i = 0;
  for (const SharedConstant& c : kSharedConstants)
    body += "  v[" + std::to_string(i++) + "] = " + c.define + ";\n";
  const std::vector<float> got =
      oneInvocationFloats(head, body, std::size(kSharedConstants), "constants test");
  i = 0;
  for (const SharedConstant& c : kSharedConstants)
    EXPECT_EQ(got[std::size_t(i++)], c.value) << c.define;
  EXPECT_EQ(std::string(kSharedConstants[1].define), "SL_SINGULAR_EPS");
  EXPECT_EQ(kSharedConstants[1].value, kSingularEps);
  // No embedded shader writes the clamp or κ by hand any more.
  for (const gpu::EmbeddedShader& s : gpu::embeddedShaders()) {
    const std::string text(s.source);
    EXPECT_EQ(text.find("1e-6 * R"), std::string::npos) << s.name;
    EXPECT_EQ(text.find("kLampDepth = 2"), std::string::npos) << s.name;
  }
}

/// What a shader's built-ins give for fixed arguments, with `prologue` before main.
std::vector<float> builtInResults(const std::string& prologue) {
  return oneInvocationFloats(prologue,
                             "  v[0] = exp(0.7);\n"
                             "  v[1] = sqrt(2.0);\n"
                             "  vec3 n = normalize(vec3(1.0, 2.0, 3.0));\n"
                             "  v[2] = n.x; v[3] = n.y; v[4] = n.z;\n"
                             "  v[5] = pow(1.3, 2.5);\n"
                             "  v[6] = log(3.0);\n"
                             "  v[7] = exp(0.0);\n"
                             "  v[8] = sqrt(0.0);\n",
                             9, "built-ins test");
}

TEST(GpuShaders, ImpreciseBuiltInsAreTheUlpsAskedAwayAndExactValuesStay) {
  SCATTERLAB_REQUIRE_GPU();
  // SCATTERLAB_GPU_IMPRECISE's prologue (the CI's second GPU run sets 4): each result of the
  // built-ins N ulps from the driver's own, either way; exp(0) = 1 and sqrt(0) = 0 untouched.
  const std::vector<float> exact = builtInResults(""),
                           off = builtInResults(gpu::imprecisePrologue(4));
  int up = 0;
  for (std::size_t i = 0; i < 7; ++i) {
    std::int32_t a, b;
    std::memcpy(&a, &exact[i], sizeof a);
    std::memcpy(&b, &off[i], sizeof b);
    EXPECT_EQ(std::abs(b - a), 4) << "result " << i << ": " << exact[i] << " vs " << off[i];
    up += b > a;
  }
  EXPECT_GT(up, 0);  // not all one way
  EXPECT_LT(up, 7);
  EXPECT_EQ(off[7], 1.0f);
  EXPECT_EQ(off[8], 0.0f);
  // The variable as the process read it (the whole suite runs with it unset and with 4).
  const char* v = std::getenv("SCATTERLAB_GPU_IMPRECISE");
  EXPECT_EQ(gpu::impreciseUlps(), v && *v ? std::atoi(v) : 0);
}

/// Runs `body` (GLSL: invocation i < uCount reads `a[]` and writes `v[]`) after `prologue` (a
/// GPU's rounding simulated, or nothing), cpu_arithmetic.glsl and `uniforms` (declarations), for
/// `count` invocations on `in`; `set` sets the uniforms. Returns `outFloats` floats of `v`.
std::vector<float> afterCpuArithmetic(const std::string& prologue, const std::string& uniforms,
                                      const std::string& body, const std::vector<float>& in,
                                      std::size_t count, std::size_t outFloats,
                                      const std::function<void(const gpu::Program&)>& set) {
  std::string src = "#version 450 core\n";
  for (const std::string& d : gpu::sharedConstantDefines()) src += "#define " + d + "\n";
  src += prologue;
  src += gpu::shaderSource("cpu_arithmetic.glsl");
  src +=
      "\nlayout(local_size_x = 64) in;\n"
      "layout(std430, binding = 0) readonly buffer In { float a[]; };\n"
      "layout(std430, binding = 1) writeonly buffer Out { float v[]; };\n"
      "uniform uint uCount;\n" +
      uniforms +
      "void main() {\n"
      "  uint i = gl_GlobalInvocationID.x;\n"
      "  if (i >= uCount) return;\n" +
      body + "}\n";
  const gpu::Shader cs(GL_COMPUTE_SHADER, src, "cpu arithmetic test");
  const gpu::Program p({&cs}, "cpu arithmetic test");
  const gpu::Buffer input(in.size() * sizeof(float), in.data(), 0, "cpu arithmetic in");
  const gpu::Buffer output(outFloats * sizeof(float), nullptr, 0, "cpu arithmetic out");
  p.use();
  glUniform1ui(p.uniform("uCount"), GLuint(count));
  if (set) set(p);
  input.bindBase(GL_SHADER_STORAGE_BUFFER, 0);
  output.bindBase(GL_SHADER_STORAGE_BUFFER, 1);
  gpu::dispatch("cpu arithmetic test", {GLuint((count + 63) / 64), 1, 1});
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  std::vector<float> got(outFloats);
  output.read(got.data(), got.size() * sizeof(float));
  return got;
}

/// The GPU's results of cpu_arithmetic.glsl's helpers and of the plain built-ins beside them, for
/// `in` (8 floats per case: a, b, x, v.xyz, len, step), with `prologue` before the helpers: per
/// case a / b, √x, |v|, v / |v| (3), stepCount(len, step) (as a float), twice (helpers, plain).
std::vector<float> cpuArithmeticOnTheGpu(const std::vector<float>& in,
                                         const std::string& prologue) {
  const std::size_t cases = in.size() / 8;
  return afterCpuArithmetic(
      prologue, "",
      "  uint s = 8u * i, o = 14u * i;\n"
      "  vec3 w = vec3(a[s + 3u], a[s + 4u], a[s + 5u]);\n"
      "  vec3 n = cpuNormalize(w), m = normalize(w);\n"
      "  v[o] = cpuDiv(a[s], a[s + 1u]);\n"
      "  v[o + 1u] = cpuSqrt(a[s + 2u]);\n"
      "  v[o + 2u] = cpuLength(w);\n"
      "  v[o + 3u] = n.x; v[o + 4u] = n.y; v[o + 5u] = n.z;\n"
      "  v[o + 6u] = float(stepCount(a[s + 6u], a[s + 7u]));\n"
      "  v[o + 7u] = a[s] / a[s + 1u];\n"
      "  v[o + 8u] = sqrt(a[s + 2u]);\n"
      "  v[o + 9u] = length(w);\n"
      "  v[o + 10u] = m.x; v[o + 11u] = m.y; v[o + 12u] = m.z;\n"
      "  v[o + 13u] = float(max(1, int(ceil(a[s + 6u] / a[s + 7u] - SL_STEP_SLACK))));\n",
      in, cases, cases * 14, nullptr);
}

// cpu_arithmetic.glsl, what every ray's set-up goes through (the camera's rays, box entries and
// exits, shadow rays, step counts): its division, square root, length, normalize and stepCount
// give the CPU's floats bit for bit — with the driver's built-ins, and with them simulated 4
// ulps off (SCATTERLAB_GPU_IMPRECISE's prologue, float and double), where the plain built-ins
// beside them do not. The step counts are asked at their edges: lengths within 16 ulps of
// (k + SL_STEP_SLACK)·step, where one ulp of the ratio gives k or k + 1 steps.
TEST(GpuShaders, TheCpuArithmeticIsTheCpusBitForBit) {
  SCATTERLAB_REQUIRE_GPU();
  std::mt19937 rng(33);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), mag(-20.0f, 20.0f);
  const auto wide = [&] { return std::ldexp(1.0f + 0.5f * unit(rng), int(mag(rng))); };
  std::vector<float> in;
  constexpr int kCases = 8192;
  for (int c = 0; c < kCases; ++c) {
    const float a = wide() * (unit(rng) < 0 ? -1.0f : 1.0f), b = wide(), x = wide();
    const Vec3 v(unit(rng), unit(rng), unit(rng));
    const float step = std::ldexp(1.0f + 0.5f * unit(rng), -int(2 + c % 9));
    const int k = 1 + c % 700;
    float len = step * (float(k) + kStepSlack);
    for (int u = c % 33 - 16; u != 0; u += u > 0 ? -1 : 1)
      len = std::nextafter(len, u > 0 ? kInfinity : 0.0f);
    in.insert(in.end(), {a, b, x, v.x, v.y, v.z, len, step});
  }
  const auto bits = [](float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
  };
  for (const int ulps : {0, 4}) {
    const std::vector<float> got =
        cpuArithmeticOnTheGpu(in, ulps ? gpu::imprecisePrologue(ulps) : std::string());
    int wrong = 0, plainOff = 0, edges = 0;
    for (int c = 0; c < kCases; ++c) {
      const float* i = &in[std::size_t(c) * 8];
      const Vec3 v(i[3], i[4], i[5]), n = glm::normalize(v);
      const float want[7] = {i[0] / i[1],
                             std::sqrt(i[2]),
                             glm::length(v),
                             n.x,
                             n.y,
                             n.z,
                             float(stepCount(i[6], i[7]))};
      const float* g = &got[std::size_t(c) * 14];
      for (int r = 0; r < 7; ++r) {
        if (bits(g[r]) != bits(want[r]) && ++wrong <= 5)
          ADD_FAILURE() << ulps << " ulps, case " << c << " result " << r << ": GPU " << g[r]
                        << ", CPU " << want[r];
        plainOff += bits(g[7 + r]) != bits(want[r]);
      }
      edges += stepCount(std::nextafter(i[6], kInfinity), i[7]) != stepCount(i[6], i[7]) ||
               stepCount(std::nextafter(i[6], 0.0f), i[7]) != stepCount(i[6], i[7]);
    }
    EXPECT_EQ(wrong, 0) << ulps << " ulps";
    std::printf(
        "built-ins %d ulps off: %d of %d helper results differ from the CPU's, %d plain "
        "built-in results; %d of %d lengths an ulp from their step count's edge\n",
        ulps, wrong, 7 * kCases, plainOff, edges, kCases);
    // The simulation moves the plain sqrt, length and normalize (nothing to show without it).
    if (ulps > 0) {
      EXPECT_GT(plainOff, kCases);
    }
  }
}

// cpuCameraRay (what every pixel's march starts from) is Camera::RayGenerator::at bit for bit:
// every pixel centre and 3 × 3 strata of an oblique 97 × 61 camera with a 41° field of view,
// with the built-ins as they are and 4 ulps off.
TEST(GpuShaders, TheCameraRaysAreTheCpusBitForBit) {
  SCATTERLAB_REQUIRE_GPU();
  Camera cam;
  cam.position = Vec3(1.6f, 1.1f, -1.5f);
  cam.lookAt = Vec3(0.45f, 0.55f, 0.5f);
  cam.fovYDeg = 41.0f;
  cam.width = 97;
  cam.height = 61;
  const Camera::RayGenerator gen = cam.rayGenerator();
  std::vector<Vec3> want;
  std::vector<float> at;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
          const float fx = float(x) + (float(i) + 0.5f) / 3.0f,
                      fy = float(y) + (float(j) + 0.5f) / 3.0f;
          at.insert(at.end(), {fx, fy});
          want.push_back(gen.at(fx, fy).dir);
        }
  for (const int ulps : {0, 4}) {
    const std::vector<float> got = afterCpuArithmetic(
        ulps ? gpu::imprecisePrologue(ulps) : std::string(),
        "uniform vec2 uSize, uTanHalf;\n"
        "uniform vec3 uForward, uRight, uUp;\n",
        "  vec3 d = cpuCameraRay(vec2(a[2u * i], a[2u * i + 1u]), uSize, uForward, uRight, uUp,\n"
        "                        uTanHalf);\n"
        "  v[3u * i] = d.x; v[3u * i + 1u] = d.y; v[3u * i + 2u] = d.z;\n",
        at, want.size(), want.size() * 3, [&](const gpu::Program& p) {
          glUniform2f(p.uniform("uSize"), float(gen.width), float(gen.height));
          glUniform2f(p.uniform("uTanHalf"), gen.sx, gen.sy);
          glUniform3f(p.uniform("uForward"), gen.forward.x, gen.forward.y, gen.forward.z);
          glUniform3f(p.uniform("uRight"), gen.right.x, gen.right.y, gen.right.z);
          glUniform3f(p.uniform("uUp"), gen.up.x, gen.up.y, gen.up.z);
        });
    int wrong = 0;
    for (std::size_t r = 0; r < want.size(); ++r)
      for (int k = 0; k < 3; ++k)
        if (std::memcmp(&got[3 * r + std::size_t(k)], &want[r][k], sizeof(float)) != 0 &&
            ++wrong <= 5)
          ADD_FAILURE() << ulps << " ulps, ray " << r << " component " << k << ": GPU "
                        << got[3 * r + std::size_t(k)] << ", CPU " << want[r][k];
    EXPECT_EQ(wrong, 0) << ulps << " ulps, " << want.size() << " rays";
  }
}

TEST(GpuPassLayer, ADispatchBeyondTheDeviceLimitIsAnErrorBeforeAnyWork) {
  SCATTERLAB_REQUIRE_GPU();
  GLint maxX = 0;
  glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0, &maxX);
  const gpu::Program& p = gpu::program({.compute = {"scan.comp.glsl"}}, "limit test");
  p.use();
  const gpu::PassCounts before = gpu::passCounts();
  try {
    gpu::dispatch("limit test", {GLuint(maxX) + 1u, 1, 1});
    FAIL() << "expected GpuError";
  } catch (const GpuError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("limit test"), std::string::npos) << m;
    EXPECT_NE(m.find(std::to_string(maxX)), std::string::npos) << m;
  }
  EXPECT_EQ(gpu::passCounts().dispatches, before.dispatches);
  gpu::checkGl("after the refused dispatch");
}

// A storage buffer above GL_MAX_SHADER_STORAGE_BLOCK_SIZE (llvmpipe: 128 MiB; GL's minimum
// 16 MiB) is refused where it is bound, naming the buffer and the limit; one at the limit binds.
TEST(GpuPassLayer, AStorageBufferAboveTheDeviceBlockSizeIsAnErrorWhereItIsBound) {
  SCATTERLAB_REQUIRE_GPU();
  GLint64 limit = 0;
  glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &limit);
  if (limit > (GLint64(1) << 28)) GTEST_SKIP() << "the device's limit is " << limit << " bytes";
  const gpu::Buffer at(std::size_t(limit), nullptr, 0, "at the limit");
  EXPECT_NO_THROW(at.bindBase(GL_SHADER_STORAGE_BUFFER, 0));
  const gpu::Buffer above(std::size_t(limit) + 4, nullptr, 0, "above the limit");
  try {
    above.bindBase(GL_SHADER_STORAGE_BUFFER, 0);
    FAIL() << "expected GpuError";
  } catch (const GpuError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("'above the limit'"), std::string::npos) << m;
    EXPECT_NE(m.find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE: " + std::to_string(limit >> 20) + " MiB"),
              std::string::npos)
        << m;
  }
  gpu::checkGl("after the refused binding");
}

TEST(GpuCli, BackendGpuWithoutContextFailsClearly) {
  const std::string dir = ::testing::TempDir();
  const std::string scene = dir + "/gpu_cli_scene.json", out = dir + "/gpu_cli_out.exr";
  std::ofstream(scene) << blobSceneDoc(8, 8, 6).dump();
  std::remove(out.c_str());
  const std::string cmd = "SCATTERLAB_NO_GPU=1 " SCATTERLAB_CLI " render " + scene + " -o " + out +
                          " --backend gpu 2> " + dir + "/gpu_cli_err.txt";
  const int rc = std::system(cmd.c_str());
  EXPECT_NE(rc, 0);
  std::ifstream err(dir + "/gpu_cli_err.txt");
  const std::string msg((std::istreambuf_iterator<char>(err)), {});
  EXPECT_NE(msg.find("no OpenGL context"), std::string::npos) << msg;
  // What to do instead, at the end (issue 25).
  EXPECT_NE(msg.find("; use --backend cpu\n"), std::string::npos) << msg;
  EXPECT_FALSE(std::ifstream(out).good()) << "no partial output on failure";
}

}  // namespace
}  // namespace scatterlab::testing
