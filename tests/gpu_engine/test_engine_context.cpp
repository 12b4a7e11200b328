/// An engine's own OpenGL context (issue 34): a Renderer renders into a context shared with the
/// engine's, leaves the engine's context current when it returns, and the engine samples the
/// image there. Its own executable: the share must be asked for before anything of scatterlab
/// touches the GPU in the process (test_gpu creates scatterlab's context in its first test).

#include <epoxy/egl.h>
#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "api/renderer.h"
#include "api/scatterlab.h"
#include "core/error.h"
#include "gpu/gpu_support.h"

namespace scatterlab::testing {
namespace {

/// The engine's context: a desktop OpenGL 4.5 core context of its own, on the first EGL
/// device that is not a software one, else on Mesa's surfaceless platform (llvmpipe).
struct EngineContext {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  std::string why;
};

EngineContext makeEngineContext() {
  EngineContext e;
  std::vector<EGLDisplay> displays;
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!client) {
    e.why = "no EGL client extensions";
    return e;
  }
  if (std::strstr(client, "EGL_EXT_platform_device")) {
    EGLDeviceEXT devices[8];
    EGLint n = 0;
    if (eglQueryDevicesEXT(8, devices, &n))
      for (EGLint i = 0; i < n; ++i) {
        const char* exts = eglQueryDeviceStringEXT(devices[i], EGL_EXTENSIONS);
        if (exts && std::strstr(exts, "EGL_MESA_device_software")) continue;
        displays.push_back(eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr));
      }
  }
  if (std::strstr(client, "EGL_MESA_platform_surfaceless"))
    displays.push_back(
        eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr));
  const EGLint attrs[] = {EGL_CONTEXT_MAJOR_VERSION,
                          4,
                          EGL_CONTEXT_MINOR_VERSION,
                          5,
                          EGL_CONTEXT_OPENGL_PROFILE_MASK,
                          EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                          EGL_NONE};
  for (EGLDisplay d : displays) {
    if (d == EGL_NO_DISPLAY || !eglInitialize(d, nullptr, nullptr)) continue;
    if (!eglBindAPI(EGL_OPENGL_API)) continue;
    const EGLContext c = eglCreateContext(d, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attrs);
    if (c == EGL_NO_CONTEXT) continue;
    if (!eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, c)) continue;
    e.display = d;
    e.context = c;
    return e;
  }
  e.why = "no EGL display gave an OpenGL 4.5 core context";
  return e;
}

/// The engine samples `texture` (w × h, RGBA) in its own context: a compute shader of its own
/// fetches every texel into a storage buffer.
std::vector<float> sampleInEngine(GLuint texture, int w, int h) {
  const char* src = R"(#version 450 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0) uniform sampler2D uImage;
layout(std430, binding = 0) writeonly buffer Out { vec4 px[]; };
uniform ivec2 uSize;
void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, uSize))) return;
  px[p.y * uSize.x + p.x] = texelFetch(uImage, p, 0);
})";
  const GLuint cs = glCreateShader(GL_COMPUTE_SHADER);
  glShaderSource(cs, 1, &src, nullptr);
  glCompileShader(cs);
  const GLuint prog = glCreateProgram();
  glAttachShader(prog, cs);
  glLinkProgram(prog);
  GLint ok = 0;
  glGetProgramiv(prog, GL_LINK_STATUS, &ok);
  EXPECT_TRUE(ok);
  GLuint buf = 0;
  const std::size_t bytes = std::size_t(w) * std::size_t(h) * 4 * sizeof(float);
  glCreateBuffers(1, &buf);
  glNamedBufferStorage(buf, GLsizeiptr(bytes), nullptr, GL_DYNAMIC_STORAGE_BIT);
  glUseProgram(prog);
  glUniform2i(glGetUniformLocation(prog, "uSize"), w, h);
  glBindTextureUnit(0, texture);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buf);
  glDispatchCompute(GLuint((w + 7) / 8), GLuint((h + 7) / 8), 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  std::vector<float> out(std::size_t(w) * std::size_t(h) * 4);
  glGetNamedBufferSubData(buf, 0, GLsizeiptr(bytes), out.data());
  glDeleteBuffers(1, &buf);
  glDeleteProgram(prog);
  glDeleteShader(cs);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  return out;
}

TEST(GpuEngineContext, ARendererDrawsIntoTheEnginesContextAndLeavesItCurrent) {
  const EngineContext e = makeEngineContext();
  if (e.context == EGL_NO_CONTEXT) GTEST_SKIP() << e.why;
  // Objects of the engine's own that are not shared between contexts (framebuffers, vertex
  // arrays, queries): scatterlab must never delete or use these names in the engine's context.
  GLuint fbo = 0, vao = 0, query = 0;
  glCreateFramebuffers(1, &fbo);
  glCreateVertexArrays(1, &vao);
  glCreateQueries(GL_TIMESTAMP, 1, &query);
  shareGlContextWithCurrent();
  EXPECT_EQ(eglGetCurrentContext(), e.context);
  {
    Json doc = blobSceneDoc(16, 32, 24);
    Renderer r(doc, ".", "gradient", "gpu");
    r.keepImageOnDevice(true);
    for (int frame = 0; frame < 2; ++frame) {
      if (frame) r.set("lights.1.position=[0.6,1.4,0.45]");
      const RenderResult res = r.render();
      EXPECT_EQ(eglGetCurrentContext(), e.context) << "frame " << frame;
      ASSERT_TRUE(res.deviceImage.has_value());
      EXPECT_EQ(res.stats.extra.at("egl_platform").get<std::string>(),
                "shared with the caller's context");
      // The texture is a name of the engine's context; sampled there it is the image.
      const RenderResult::DeviceImage& d = *res.deviceImage;
      EXPECT_TRUE(glIsTexture(d.texture));
      const std::vector<float> sampled = sampleInEngine(d.texture, d.width, d.height);
      r.keepImageOnDevice(false);
      const RenderResult back = r.render();  // the same frame, read back by scatterlab
      r.keepImageOnDevice(true);
      EXPECT_EQ(eglGetCurrentContext(), e.context);
      ASSERT_EQ(back.image.pixels().size(), std::size_t(d.width) * std::size_t(d.height));
      double worst = 0.0, peak = 0.0;
      for (std::size_t i = 0; i < back.image.pixels().size(); ++i)
        for (int c = 0; c < 3; ++c) {
          worst = std::max(
              worst, double(std::abs(sampled[4 * i + std::size_t(c)] - back.image.pixels()[i][c])));
          peak = std::max(peak, double(back.image.pixels()[i][c]));
        }
      EXPECT_GT(peak, 0.0);
      // Measured on llvmpipe: 0 (the same volume marched by the same pass).
      EXPECT_EQ(worst, 0.0) << "frame " << frame;
    }
  }
  // The Renderer is gone (its GL objects deleted in scatterlab's context): the engine's
  // context is current and its own objects are alive.
  EXPECT_EQ(eglGetCurrentContext(), e.context);
  EXPECT_TRUE(glIsFramebuffer(fbo));
  EXPECT_TRUE(glIsVertexArray(vao));
  EXPECT_TRUE(glIsQuery(query));
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  // Asking again for the same context is fine; scatterlab's context stays shared with it.
  EXPECT_NO_THROW(shareGlContextWithCurrent());
}

}  // namespace
}  // namespace scatterlab::testing
