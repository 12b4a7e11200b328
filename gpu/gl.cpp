#include "gpu/gl.h"

#include <cstring>
#include <string>
#include <vector>

#include "core/error.h"

namespace scatterlab::gpu {

namespace {

const char* glErrorName(GLenum e) {
  switch (e) {
    case GL_INVALID_ENUM:
      return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE:
      return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION:
      return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION:
      return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY:
      return "GL_OUT_OF_MEMORY";
    case GL_STACK_UNDERFLOW:
      return "GL_STACK_UNDERFLOW";
    case GL_STACK_OVERFLOW:
      return "GL_STACK_OVERFLOW";
    default:
      return "unknown GL error";
  }
}

void label(GLenum identifier, GLuint id, std::string_view name) {
  if (!name.empty()) glObjectLabel(identifier, id, GLsizei(name.size()), name.data());
}

}  // namespace

void checkGl(std::string_view pass) {
  std::string errors;
  for (int i = 0; i < 16; ++i) {
    const GLenum e = glGetError();
    if (e == GL_NO_ERROR) break;
    errors += (errors.empty() ? "" : ", ") + std::string(glErrorName(e));
  }
  if (!errors.empty()) throw GpuError("OpenGL error after " + std::string(pass) + ": " + errors);
}

Buffer::Buffer(std::size_t bytes, const void* data, GLbitfield flags, std::string_view name)
    : size_(bytes) {
  glCreateBuffers(1, &id_);
  // Zero-sized storage is an error in GL; keep one word so empty sets still bind.
  glNamedBufferStorage(id_, GLsizeiptr(bytes ? bytes : 4), bytes ? data : nullptr, flags);
  label(GL_BUFFER, id_, name);
}

void Buffer::read(void* dst, std::size_t n, std::size_t offset) const {
  if (n) glGetNamedBufferSubData(id_, GLintptr(offset), GLsizeiptr(n), dst);
}

Texture::Texture(GLenum target, std::string_view name) : target_(target) {
  glCreateTextures(target, 1, &id_);
  label(GL_TEXTURE, id_, name);
}

Texture Texture::make2D(GLenum format, int w, int h, std::string_view name) {
  Texture t(GL_TEXTURE_2D, name);
  glTextureStorage2D(t.id_, 1, format, w, h);
  glTextureParameteri(t.id_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(t.id_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  return t;
}

Texture Texture::make3D(GLenum format, int w, int h, int d, std::string_view name) {
  Texture t(GL_TEXTURE_3D, name);
  glTextureStorage3D(t.id_, 1, format, w, h, d);
  glTextureParameteri(t.id_, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(t.id_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
    glTextureParameteri(t.id_, wrap, GL_CLAMP_TO_EDGE);
  return t;
}

Texture Texture::make2DArray(GLenum format, int w, int h, int layers, std::string_view name) {
  Texture t(GL_TEXTURE_2D_ARRAY, name);
  glTextureStorage3D(t.id_, 1, format, w, h, layers);
  glTextureParameteri(t.id_, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(t.id_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T})
    glTextureParameteri(t.id_, wrap, GL_CLAMP_TO_EDGE);
  return t;
}

Framebuffer::Framebuffer(std::string_view name) {
  glCreateFramebuffers(1, &id_);
  label(GL_FRAMEBUFFER, id_, name);
}

Shader::Shader(GLenum stage, std::string_view source, std::string_view file) {
  id_ = glCreateShader(stage);
  const char* src = source.data();
  const GLint len = GLint(source.size());
  glShaderSource(id_, 1, &src, &len);
  glCompileShader(id_);
  GLint ok = 0;
  glGetShaderiv(id_, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetShaderiv(id_, GL_INFO_LOG_LENGTH, &n);
    std::string log(size_t(std::max(n, 1)), '\0');
    glGetShaderInfoLog(id_, n, nullptr, log.data());
    log.resize(std::strlen(log.c_str()));
    throw GpuError("shader " + std::string(file) + " failed to compile:\n" + log);
  }
  label(GL_SHADER, id_, file);
}

Program::Program(std::initializer_list<const Shader*> shaders, std::string_view name) {
  id_ = glCreateProgram();
  for (const Shader* s : shaders) glAttachShader(id_, s->id());
  glLinkProgram(id_);
  for (const Shader* s : shaders) glDetachShader(id_, s->id());
  GLint ok = 0;
  glGetProgramiv(id_, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetProgramiv(id_, GL_INFO_LOG_LENGTH, &n);
    std::string log(size_t(std::max(n, 1)), '\0');
    glGetProgramInfoLog(id_, n, nullptr, log.data());
    log.resize(std::strlen(log.c_str()));
    throw GpuError("program " + std::string(name) + " failed to link:\n" + log);
  }
  label(GL_PROGRAM, id_, name);
}

Query::Query(GLenum target, std::string_view name) {
  glCreateQueries(target, 1, &id_);
  label(GL_QUERY, id_, name);
}

VertexArray::VertexArray(std::string_view name) {
  glCreateVertexArrays(1, &id_);
  label(GL_VERTEX_ARRAY, id_, name);
}

}  // namespace scatterlab::gpu
