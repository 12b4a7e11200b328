#pragma once
/// Move-only RAII wrappers, one per OpenGL object type (DESIGN.md §8), and GL error checks.
/// Every constructor that creates an object and every member function needs the context of
/// gpu::context() current on the calling thread; destructors and moves of empty objects do not.
/// Move-assignment swaps, so the moved-from object releases the old name when it dies.
/// Raw GLuint names stay inside gpu/: the accessors below are for gpu/ code only.

#include <epoxy/gl.h>

#include <string>
#include <string_view>
#include <utility>

namespace scatterlab::gpu {

/// Throws GpuError naming `pass` when glGetError reports anything (draining the queue).
void checkGl(std::string_view pass);

/// Base of the wrappers: owns one GL name, deleted through Deleter.
template <class Deleter>
class GlObject {
 public:
  GlObject() = default;
  explicit GlObject(GLuint id) : id_(id) {}
  ~GlObject() {
    if (id_) Deleter{}(id_);
  }
  GlObject(const GlObject&) = delete;
  GlObject& operator=(const GlObject&) = delete;
  GlObject(GlObject&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
  GlObject& operator=(GlObject&& o) noexcept {
    std::swap(id_, o.id_);
    return *this;
  }
  GLuint id() const { return id_; }
  explicit operator bool() const { return id_ != 0; }

 protected:
  GLuint id_ = 0;
};

struct BufferDeleter {
  void operator()(GLuint id) const { glDeleteBuffers(1, &id); }
};
struct TextureDeleter {
  void operator()(GLuint id) const { glDeleteTextures(1, &id); }
};
struct FramebufferDeleter {
  void operator()(GLuint id) const { glDeleteFramebuffers(1, &id); }
};
struct ShaderDeleter {
  void operator()(GLuint id) const { glDeleteShader(id); }
};
struct ProgramDeleter {
  void operator()(GLuint id) const { glDeleteProgram(id); }
};
struct QueryDeleter {
  void operator()(GLuint id) const { glDeleteQueries(1, &id); }
};
struct VertexArrayDeleter {
  void operator()(GLuint id) const { glDeleteVertexArrays(1, &id); }
};

/// Buffer object with immutable storage (glNamedBufferStorage).
class Buffer : public GlObject<BufferDeleter> {
 public:
  Buffer() = default;
  /// Creates `bytes` of storage initialised from `data` (may be null); `label` for debuggers.
  Buffer(std::size_t bytes, const void* data, GLbitfield flags, std::string_view label);
  std::size_t size() const { return size_; }
  /// Copies bytes [offset, offset + n) back to host memory.
  void read(void* dst, std::size_t n, std::size_t offset = 0) const;
  void bindBase(GLenum target, GLuint index) const { glBindBufferBase(target, index, id_); }

 private:
  std::size_t size_ = 0;
};

/// Texture object (glCreateTextures) with immutable storage.
class Texture : public GlObject<TextureDeleter> {
 public:
  Texture() = default;
  /// A 2D texture of `format` (sized internal format).
  static Texture make2D(GLenum format, int w, int h, std::string_view label);
  /// A 3D texture of `format`, GL_LINEAR filtering, CLAMP_TO_EDGE: lookups at normalised
  /// coordinates (u + 0.5) / dims match Grid3::sampleIndex(u) inside the box.
  static Texture make3D(GLenum format, int w, int h, int d, std::string_view label);
  /// A 2D array texture of `layers` layers, GL_LINEAR filtering, CLAMP_TO_EDGE.
  static Texture make2DArray(GLenum format, int w, int h, int layers, std::string_view label);
  GLenum target() const { return target_; }

 private:
  Texture(GLenum target, std::string_view label);
  GLenum target_ = 0;
};

/// Framebuffer object.
class Framebuffer : public GlObject<FramebufferDeleter> {
 public:
  Framebuffer() = default;
  explicit Framebuffer(std::string_view label);
};

/// A compiled shader stage; compile errors throw GpuError with `file` and the info log.
class Shader : public GlObject<ShaderDeleter> {
 public:
  Shader() = default;
  Shader(GLenum stage, std::string_view source, std::string_view file);
};

/// A linked program; link errors throw GpuError with the files and the info log.
class Program : public GlObject<ProgramDeleter> {
 public:
  Program() = default;
  Program(std::initializer_list<const Shader*> shaders, std::string_view label);
  void use() const { glUseProgram(id_); }
  /// Location of uniform `name`, or -1 (unused uniforms are optimised away; setting -1 is a
  /// no-op in GL, so callers need not check).
  GLint uniform(const char* name) const { return glGetUniformLocation(id_, name); }
};

/// Query object (timer queries for per-stage GPU times).
class Query : public GlObject<QueryDeleter> {
 public:
  Query() = default;
  Query(GLenum target, std::string_view label);
};

/// Vertex array object; the stages draw attribute-less geometry generated from gl_VertexID and
/// gl_InstanceID, but core profile still needs one bound.
class VertexArray : public GlObject<VertexArrayDeleter> {
 public:
  VertexArray() = default;
  explicit VertexArray(std::string_view label);
};

}  // namespace scatterlab::gpu
