/// GL validation (gpu/validate.h): the memory hazards llvmpipe forgives and a GPU does not are
/// errors that name the programs, the object and the barrier bit missing; the right barrier, or
/// `readonly` where a shader only reads, is none.

#include <cstdlib>
#include <string>
#include <vector>

#include "core/error.h"
#include "gpu/bindings.h"
#include "gpu/context.h"
#include "gpu/dispatch.h"
#include "gpu/gl.h"
#include "gpu/shaders.h"
#include "gpu/validate.h"
#include "gpu_support.h"

namespace scatterlab::testing {
namespace {

/// A compute program from GLSL after the #version line (linked after validation is installed,
/// so that its sources are known to it).
gpu::Program program(const std::string& body, const std::string& label) {
  const gpu::Shader cs(GL_COMPUTE_SHADER,
                       "#version 450 core\nlayout(local_size_x = 1) in;\n" + body, label);
  return gpu::Program({&cs}, label);
}

// One program writes binding 0; another (with `readonly` only under a #define, as the variants
// of the shaders are written) reads binding 0 into binding 1.
const char* kWrite =
    "layout(std430, binding = 0) writeonly buffer A { uint a[]; };\n"
    "void main() { a[0] = 7u; }\n";
const char* kRead =
    "#define READ_ONLY_A\n"
    "#ifdef READ_ONLY_A\n"
    "layout(std430, binding = 0) readonly buffer A { uint a[]; };\n"
    "#else\n"
    "layout(std430, binding = 0) buffer A { uint a[]; };\n"
    "#endif\n"
    "layout(std430, binding = 1) writeonly buffer B { uint b[]; };\n"
    "void main() { b[0] = a[0] + 1u; }\n";

class GpuValidate : public ::testing::Test {
 protected:
  void SetUp() override {
    SCATTERLAB_REQUIRE_GPU();
    gpu::context();
    gpu::installValidation();  // a no-op under ctest, which sets SCATTERLAB_GPU_VALIDATE
    ASSERT_TRUE(gpu::validating());
    glMemoryBarrier(GL_ALL_BARRIER_BITS);  // nothing pending from earlier tests
  }
  /// Runs `f`, expecting a GpuError whose message holds every one of `parts`.
  template <class F>
  void expectHazard(F f, std::initializer_list<std::string> parts) {
    try {
      f();
      ADD_FAILURE() << "no hazard reported";
    } catch (const GpuError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("GL hazard"), std::string::npos) << m;
      for (const std::string& p : parts)
        EXPECT_NE(m.find(p), std::string::npos) << p << " in " << m;
    }
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
  }
};

TEST_F(GpuValidate, AReadOfAShaderWriteWithoutTheBarrierIsAnError) {
  const gpu::Program write = program(kWrite, "test write"), read = program(kRead, "test read");
  const gpu::Buffer a(16, nullptr, 0, "test a"), b(16, nullptr, 0, "test b");
  a.bindBase(GL_SHADER_STORAGE_BUFFER, 0);
  b.bindBase(GL_SHADER_STORAGE_BUFFER, 1);
  write.use();
  gpu::dispatch("test write", {1, 1, 1});
  read.use();
  expectHazard(
      [&] {
        gpu::dispatch("test read", {1, 1, 1});
      },
      {"'test read'", "'test write'", "'test a'", "GL_SHADER_STORAGE_BARRIER_BIT"});

  // With the barrier: no error, and the value arrives.
  write.use();
  gpu::dispatch("test write", {1, 1, 1});
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  read.use();
  gpu::dispatch("test read", {1, 1, 1});
  GLuint got = 0;
  b.read(&got, sizeof got);  // read() issues GL_BUFFER_UPDATE_BARRIER_BIT itself
  EXPECT_EQ(got, 8u);
  // A read-back straight from GL, without its barrier, is one.
  write.use();
  gpu::dispatch("test write", {1, 1, 1});
  expectHazard([&] { glGetNamedBufferSubData(a.id(), 0, sizeof got, &got); },
               {"read-back", "'test a'", "GL_BUFFER_UPDATE_BARRIER_BIT"});
}

TEST_F(GpuValidate, ReadOnlyBindingsReadTwiceAreNoHazardAndDisjointRangesAreApart) {
  const gpu::Program read = program(kRead, "test read");
  const gpu::Program write = program(kWrite, "test write");
  const gpu::Buffer a(512, nullptr, 0, "test a"), b(16, nullptr, 0, "test b");
  a.bindBase(GL_SHADER_STORAGE_BUFFER, 0);
  b.bindBase(GL_SHADER_STORAGE_BUFFER, 1);
  read.use();
  gpu::dispatch("test read", {1, 1, 1});
  gpu::dispatch("test read", {1, 1, 1});  // a is read only; b written only: nothing to see
  // A write to bytes [256, 512) does not touch a read of [0, 256).
  glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 0, a.id(), 256, 256);
  write.use();
  gpu::dispatch("test write", {1, 1, 1});
  glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 0, a.id(), 0, 256);
  read.use();
  gpu::dispatch("test read", {1, 1, 1});
  glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 0, a.id(), 0, 512);
  expectHazard([&] { gpu::dispatch("test read", {1, 1, 1}); }, {"bytes 256–512"});
}

TEST_F(GpuValidate, AShaderReadingPastABuffersSizeReadsPoisonNotZero) {
  // 75 uints asked for (300 bytes; storage 384, the size class): a shader that copies 76 reads
  // the 76th from the poison, 0xffffffff, where llvmpipe's bounds checks alone would give 0 and
  // a GPU whatever lies in memory there.
  std::vector<GLuint> in(75);
  for (std::size_t i = 0; i < in.size(); ++i) in[i] = GLuint(i + 1);
  gpu::Buffer a(in.size() * sizeof(GLuint), in.data(), 0, "test 75 uints");
  const gpu::Buffer b(76 * sizeof(GLuint), nullptr, 0, "test copy");
  const gpu::Program copy = program(
      "layout(std430, binding = 0) readonly buffer A { uint a[]; };\n"
      "layout(std430, binding = 1) writeonly buffer B { uint b[]; };\n"
      "void main() { for (int i = 0; i < 76; ++i) b[i] = a[i]; }\n",
      "test copy one past");
  const auto run = [&] {
    a.bindBase(GL_SHADER_STORAGE_BUFFER, 0);
    b.bindBase(GL_SHADER_STORAGE_BUFFER, 1);
    copy.use();
    gpu::dispatch("test copy one past", {1, 1, 1});
    std::vector<GLuint> out(76);
    b.read(out.data(), out.size() * sizeof(GLuint));
    return out;
  };
  std::vector<GLuint> out = run();
  EXPECT_EQ(out[0], 1u);
  EXPECT_EQ(out[74], 75u);
  EXPECT_EQ(out[75], 0xffffffffu);
  // A buffer made without data reads 0 up to its size, the poison past it; extendTo gives what
  // it takes back as 0, as such a buffer starts.
  ASSERT_TRUE(a.extendTo(76 * sizeof(GLuint)));
  out = run();
  EXPECT_EQ(out[74], 75u);
  EXPECT_EQ(out[75], 0u);
}

TEST_F(GpuValidate, ATexelFetchOutsideItsTextureNamesThePass) {
  // The empty-space grid's pass over a 4³ density told it is 8³: it fetches texels 4–7, which
  // GL leaves undefined (llvmpipe: 0). Told the truth, it fetches none.
  if (gpu::loopIterationLimit() <= 0) GTEST_SKIP() << "checked only where the loop guard is";
  const gpu::Texture density = gpu::Texture::make3D(GL_R32F, 4, 4, 4, "test density");
  const gpu::Texture grid = gpu::Texture::make3D(GL_R32F, 1, 1, 1, "test grid");
  // A define of its own: a fresh program, compiled under validation and under this label. In
  // one process (test_gpu run whole, as scripts/gpu-report.sh does) the plain variant was
  // built by an earlier test, before validation was installed and under another label.
  const gpu::Program& p = gpu::program(
      {.compute = {"common.glsl", "block_max.comp.glsl"}, .defines = {"SL_TEST_FETCH_OUTSIDE"}},
      "test empty-space grid");
  for (const int told : {8, 4}) {
    gpu::resetLoopGuard();
    p.use();
    glBindTextureUnit(gpu::binding::kDensityTexture, density.id());
    gpu::setIVec3(p, "uDensityDims", IVec3(told));
    gpu::setIVec3(p, "uBlockCount", IVec3(1));
    glBindImageTexture(gpu::binding::kBlockMaxImage, grid.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY,
                       GL_R32F);
    gpu::dispatch("test empty-space grid", {1, 1, 1});
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
    // The program's label names its define too: "test empty-space grid [SL_TEST_FETCH_OUTSIDE]".
    EXPECT_EQ(gpu::fetchOutside(), told == 8 ? "test empty-space grid [SL_TEST_FETCH_OUTSIDE]" : "")
        << told;
  }
}

TEST_F(GpuValidate, AVariableReadBeforeItIsWrittenIsAnErrorNamingTheShader) {
  // Mesa warns of it; llvmpipe reads 0 there, a GPU whatever its register held. Validation turns
  // Mesa's shader cache off, unless the caller turned it on (the sanitizer and imprecise runs
  // of the CI, after the Release run has checked the same texts): a cached text skips its
  // compile and its log.
  const char* set = std::getenv("MESA_SHADER_CACHE_DISABLE");
  const std::string cache = set ? set : "";
  if (cache == "false" || cache == "0" || cache == "no")
    GTEST_SKIP() << "Mesa's shader cache is on (MESA_SHADER_CACHE_DISABLE=" << cache << ")";
  // Validation installed by this fixture, not from the start (test_gpu run whole without
  // SCATTERLAB_GPU_VALIDATE): Mesa read its cache setting when the context was made, before
  // validation turned the cache off.
  if (!std::getenv("SCATTERLAB_GPU_VALIDATE"))
    GTEST_SKIP() << "validation was not on from the start (SCATTERLAB_GPU_VALIDATE unset), so "
                    "Mesa's shader cache may be on";
  const char* body =
      "layout(std430, binding = 0) writeonly buffer A { float a[]; };\n"
      "void main() { float x; a[0] = x + 1.0; }\n";
  try {
    const gpu::Program p = program(body, "test uninitialised");
    // A driver whose front end does not warn (not Mesa) compiles it: nothing to check there.
    if (std::string(reinterpret_cast<const char*>(glGetString(GL_VENDOR))).find("Mesa") !=
        std::string::npos)
      ADD_FAILURE() << "compiled without an error";
  } catch (const GpuError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("test uninitialised compiled with a warning"), std::string::npos) << m;
    EXPECT_NE(m.find("used uninitialized"), std::string::npos) << m;
  }
  // Written first, the same shader compiles.
  EXPECT_NO_THROW(
      program("layout(std430, binding = 0) writeonly buffer A { float a[]; };\n"
              "void main() { float x = 2.0; a[0] = x + 1.0; }\n",
              "test initialised"));
}

TEST_F(GpuValidate, TwoTransfersSideBySideOverwriteAShaderWriteOverBoth) {
  // A shader writes all of a (the whole binding); an upload of its first 16 bytes and a clear
  // of the rest leave nothing of that write for a later read to wait for. The upload alone
  // leaves the rest pending.
  const gpu::Program write = program(
      "layout(std430, binding = 0) writeonly buffer A { uint a[]; };\n"
      "void main() { for (int i = 0; i < 8; ++i) a[i] = 7u; }\n",
      "test write all");
  const gpu::Program read = program(kRead, "test read");
  const gpu::Buffer a(32, nullptr, 0, "test a"), b(16, nullptr, 0, "test b");
  const GLuint zeros[4] = {};
  GLint64 size = 0;  // 32 bytes and, under validation, the poison past them
  glGetNamedBufferParameteri64v(a.id(), GL_BUFFER_SIZE, &size);
  for (const bool both : {false, true}) {
    a.bindBase(GL_SHADER_STORAGE_BUFFER, 0);
    b.bindBase(GL_SHADER_STORAGE_BUFFER, 1);
    write.use();
    gpu::dispatch("test write all", {1, 1, 1});
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);  // what the transfers need
    glNamedBufferSubData(a.id(), 0, sizeof zeros, zeros);
    if (both)
      glClearNamedBufferSubData(a.id(), GL_R8UI, 16, GLsizeiptr(size - 16), GL_RED_INTEGER,
                                GL_UNSIGNED_BYTE, nullptr);
    read.use();
    if (both)
      gpu::dispatch("test read", {1, 1, 1});
    else
      expectHazard(
          [&] {
            gpu::dispatch("test read", {1, 1, 1});
          },
          {"'test write all'", "bytes 16–"});
  }
}

TEST_F(GpuValidate, AnIndirectSizeAndATextureFetchNeedTheirOwnBits) {
  // The sizes of an indirect dispatch, written by a shader: GL_COMMAND_BARRIER_BIT.
  const gpu::Program sizes = program(
      "layout(std430, binding = 0) writeonly buffer S { uvec3 s; };\n"
      "void main() { s = uvec3(1u); }\n",
      "test sizes");
  const gpu::Program nothing = program("void main() {}\n", "test nothing");
  const gpu::Buffer args(16, nullptr, 0, "test sizes buffer");
  args.bindBase(GL_SHADER_STORAGE_BUFFER, 0);
  sizes.use();
  gpu::dispatch("test sizes", {1, 1, 1});
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);  // not the bit an indirect dispatch needs
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, args.id());
  nothing.use();
  expectHazard([&] { gpu::dispatchIndirect("test nothing", 0); },
               {"indirect", "'test sizes buffer'", "GL_COMMAND_BARRIER_BIT"});
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);

  // An image store, then a sampler fetch of the same texture: GL_TEXTURE_FETCH_BARRIER_BIT.
  const gpu::Program store = program(
      "layout(r32f, binding = 0) writeonly uniform image2D uOut;\n"
      "void main() { imageStore(uOut, ivec2(0), vec4(1.0)); }\n",
      "test store");
  const gpu::Program fetch = program(
      "uniform sampler2D uIn;\n"
      "layout(std430, binding = 1) writeonly buffer B { float b; };\n"
      "void main() { b = texelFetch(uIn, ivec2(0), 0).r; }\n",
      "test fetch");
  const gpu::Texture t = gpu::Texture::make2D(GL_R32F, 1, 1, "test texture");
  const gpu::Buffer b(16, nullptr, 0, "test b");
  b.bindBase(GL_SHADER_STORAGE_BUFFER, 1);
  glBindImageTexture(0, t.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
  store.use();
  gpu::dispatch("test store", {1, 1, 1});
  glBindTextureUnit(0, t.id());
  fetch.use();
  glUniform1i(fetch.uniform("uIn"), 0);
  expectHazard(
      [&] {
        gpu::dispatch("test fetch", {1, 1, 1});
      },
      {"samples texture unit 0", "'test texture'", "'test store'", "GL_TEXTURE_FETCH_BARRIER_BIT"});
  store.use();
  gpu::dispatch("test store", {1, 1, 1});
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
  fetch.use();
  gpu::dispatch("test fetch", {1, 1, 1});
  float got = 0.0f;
  b.read(&got, sizeof got);
  EXPECT_EQ(got, 1.0f);
  glBindTextureUnit(0, 0);
  glBindImageTexture(0, 0, 0, GL_FALSE, 0, GL_READ_ONLY, GL_R32F);
}

TEST_F(GpuValidate, AProgramAboveWhatADesktopGpuAllowsIsAnError) {
  // Nine image uniforms run on llvmpipe (32) and not on NVIDIA (8).
  std::string body, sum;
  for (int i = 0; i < 9; ++i) {
    body += "layout(r32f, binding = 0) readonly uniform image2D uImage" + std::to_string(i) + ";\n";
    sum += " + imageLoad(uImage" + std::to_string(i) + ", ivec2(0)).r";
  }
  body +=
      "layout(std430, binding = 0) writeonly buffer B { float b; };\n"
      "void main() { b = 0.0" +
      sum + "; }\n";
  // Where the device itself allows fewer than nine (NVIDIA), its compiler or linker refuses the
  // program first, and that error names it; elsewhere the portability check does.
  GLint deviceLimit = 0;
  glGetIntegerv(GL_MAX_COMPUTE_IMAGE_UNIFORMS, &deviceLimit);
  try {
    program(body, "test nine images");
    FAIL() << "no error";
  } catch (const GpuError& e) {
    const std::string m = e.what();
    if (deviceLimit < 9) {
      EXPECT_NE(m.find("test nine images"), std::string::npos) << m;
    } else {
      EXPECT_NE(m.find("GL portability"), std::string::npos) << m;
      EXPECT_NE(m.find("'test nine images' uses 9 image uniforms, above the 8"), std::string::npos)
          << m;
    }
  }
}

}  // namespace
}  // namespace scatterlab::testing
