/// GL foundations: context, RAII wrappers, embedded shaders and their failure paths.

#include <cstdlib>
#include <fstream>

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

TEST(GpuShaders, EveryEmbeddedFileIsPresent) {
  // No context needed: the table is compiled into the library.
  for (const char* f :
       {"common.glsl", "volume_tracer.comp.glsl", "per_voxel.comp.glsl", "density_splat.vert.glsl",
        "density_splat.frag.glsl", "radiance_splat.vert.glsl", "radiance_splat.frag.glsl",
        "radiance_normalize.comp.glsl", "fullscreen.vert.glsl", "slice_march.frag.glsl"})
    EXPECT_FALSE(gpu::shaderSource(f).empty()) << f;
  EXPECT_THROW(gpu::shaderSource("nope.glsl"), GpuError);
}

TEST(GpuShaders, EveryProgramCompilesAndLinks) {
  SCATTERLAB_REQUIRE_GPU();
  EXPECT_NO_THROW(
      gpu::computeProgram({"common.glsl", "volume_tracer.comp.glsl"}, {"SL_GRADIENTS"}, "t"));
  EXPECT_NO_THROW(
      gpu::computeProgram({"common.glsl", "volume_tracer.comp.glsl"}, {"SL_HW_FILTER"}, "t"));
  EXPECT_NO_THROW(gpu::computeProgram({"common.glsl", "per_voxel.comp.glsl"}, {}, "t"));
  EXPECT_NO_THROW(gpu::computeProgram({"radiance_normalize.comp.glsl"}, {}, "t"));
  EXPECT_NO_THROW(gpu::graphicsProgram({"fullscreen.vert.glsl"},
                                       {"common.glsl", "slice_march.frag.glsl"}, {}, "t"));
  gpu::checkGl("compiling every program");
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
  EXPECT_FALSE(std::ifstream(out).good()) << "no partial output on failure";
}

}  // namespace
}  // namespace scatterlab::testing
