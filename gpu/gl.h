#pragma once
/// Move-only RAII wrappers, one per OpenGL object type (DESIGN.md §8), and GL error checks.
/// Every constructor that creates an object and every member function needs the context of
/// gpu::context() current on the calling thread; destructors and moves of empty objects do not.
/// Move-assignment swaps, so the moved-from object releases the old name when it dies.
/// Raw GLuint names stay inside gpu/: the accessors below are for gpu/ code only.
///
/// Recycling (issue 14, GL objects reused across frames): while a RecyclingScope lives (a
/// GpuFrame holds one, so a Renderer's kept frame keeps recycling on from one render to the
/// next), a Buffer, Texture, Framebuffer, Query or VertexArray that dies is not deleted but kept
/// in a free list, and the next one made with the same description (buffer: bytes and flags;
/// texture: target, format and size; query: target) takes its name over instead of creating a
/// new object. A taken object reads as a new one: buffers get their data (or zeros), textures
/// are cleared to zero (unless Texture::Contents::Overwritten), framebuffers lose their
/// attachments. New objects are cleared the same way: GL leaves new storage undefined. When the
/// last scope ends, the free list is deleted. glObjectCounts() counts creations and reuses (for the
/// reuse tests).

#include <epoxy/gl.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace scatterlab::gpu {

/// Throws GpuError naming `pass` when glGetError reports anything (draining the queue).
void checkGl(std::string_view pass);

/// Host waits (issue 33): every call in gpu/ that blocks the host until the GPU has finished
/// work (a read-back of a buffer or texture, glFinish, a query result) counts itself here, so a
/// frame can report how many times it stopped for the GPU. The final image's read-back is
/// counted apart, with its wall time. No context needed to read them.
struct HostWaitCounts {
  long long waits = 0;           ///< blocking calls other than the image read-back
  long long imageReadbacks = 0;  ///< read-backs of a final image (readScreenImage)
  double imageReadbackMs = 0.0;  ///< their host wall time
};
HostWaitCounts hostWaitCounts();
/// Counts one blocking call (`what` is for debugging: SCATTERLAB_TRACE_WAITS=1 prints it).
void countHostWait(std::string_view what);
/// Counts one final-image read-back that took `ms` of host time.
void countImageReadback(double ms);

/// What the wrappers did since the process started (no context needed).
struct GlObjectCounts {
  long long created = 0;  ///< objects created (glCreate*): buffers, textures, framebuffers,
                          ///< queries, vertex arrays, shaders, programs
  long long reused = 0;   ///< objects taken from the free list instead of created
  long long live = 0;     ///< objects owned by a wrapper now
  long long free = 0;     ///< objects in the free list now
};
GlObjectCounts glObjectCounts();

/// Turns recycling on for its lifetime (scopes nest; the free list is deleted, in the current
/// context, when the last one ends). Constructing one needs no context.
class RecyclingScope {
 public:
  RecyclingScope();
  ~RecyclingScope();
  RecyclingScope(const RecyclingScope&) = delete;
  RecyclingScope& operator=(const RecyclingScope&) = delete;
};

namespace detail {
/// The GL object types the wrappers own (and delete by their own glDelete*).
enum class ObjectKind { None, Buffer, Texture, Framebuffer, Query, VertexArray };
/// What a recycled object must match to be taken over.
struct ObjectKey {
  ObjectKind kind = ObjectKind::None;
  GLenum target = 0, format = 0;
  int w = 0, h = 0, d = 0;
  std::size_t bytes = 0;
  GLbitfield flags = 0;
  bool operator==(const ObjectKey&) const = default;
};
/// A name from the free list matching `key` (0: none, or recycling is off).
GLuint takeRecycled(const ObjectKey& key);
/// Keeps `id` in the free list under `key` when recycling is on (returns true), else false.
bool recycle(const ObjectKey& key, GLuint id);
/// Counts an object created / deleted by a wrapper.
void countCreated();
void countDeleted();
/// Whether a GL context is current on this thread.
bool contextCurrent();
}  // namespace detail

/// Base of the wrappers: owns one GL name, deleted through Deleter.
template <class Deleter>
class GlObject {
 public:
  GlObject() = default;
  explicit GlObject(GLuint id) : id_(id) {}
  ~GlObject() {
    // Without a current context (an error unwinding on a thread the context is not current on)
    // the name is left to the driver: a GL call there would abort the process (libepoxy).
    if (id_ && detail::contextCurrent()) {
      Deleter{}(id_);
      detail::countDeleted();
    }
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
  /// Gives the name to the free list (a derived destructor's first step); the base destructor
  /// then deletes nothing.
  void release(const detail::ObjectKey& key) {
    if (id_ && detail::recycle(key, id_)) id_ = 0;
  }
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
  /// GL_DYNAMIC_STORAGE_BIT is always added to `flags` (so that a recycled buffer can take new
  /// data).
  Buffer(std::size_t bytes, const void* data, GLbitfield flags, std::string_view label);
  ~Buffer() { release(key()); }
  Buffer(Buffer&& o) noexcept
      : GlObject(std::move(o)), size_(o.size_), storage_(o.storage_), flags_(o.flags_) {}
  Buffer& operator=(Buffer&& o) noexcept {
    GlObject::operator=(std::move(o));
    std::swap(size_, o.size_);
    std::swap(storage_, o.storage_);
    std::swap(flags_, o.flags_);
    return *this;
  }
  /// The storage a buffer of `bytes` gets: `bytes` up to 256 bytes, above that rounded up to the
  /// next quarter of its power of two (at most 25 % more; above 1 MiB the next eighth, 12.5 %). A
  /// recycled buffer is taken over by a request of the same storage, so a set whose size changes a
  /// little from frame to frame (the samples of adaptive with the per-voxel fallback as a light
  /// moves) reuses its buffers instead of creating new ones (tests/gpu/test_resident.cpp,
  /// GpuRendererReuse).
  static std::size_t storageFor(std::size_t bytes);
  /// The bytes to ask for when a buffer kept between frames is too small for `bytes`: a quarter
  /// more, so that a set that grows a little from frame to frame (adaptive's samples as a light
  /// moves) grows its buffers once, not in every frame that crosses a size class; never above
  /// maxStorageBlock() where `bytes` is not.
  static std::size_t grownFor(std::size_t bytes);
  std::size_t size() const { return size_; }
  /// Makes size() at least `bytes` where the storage holds them (the size class's room) and
  /// returns true; returns false and changes nothing where it does not.
  bool extendTo(std::size_t bytes);
  /// Copies bytes [offset, offset + n) back to host memory.
  void read(void* dst, std::size_t n, std::size_t offset = 0) const;
  /// Under validation (gpu/validate.h) every buffer's storage has this many bytes more, and its
  /// bytes past size() are 0xff (a float NaN, a uint 0xffffffff, an int −1): a shader that
  /// reads past what was asked for reads them, an image the tests see differ, where llvmpipe's
  /// bounds checks read 0 and a GPU reads whatever lies there. extendTo clears what it takes
  /// back to 0, as a buffer made without data starts.
  static constexpr std::size_t kPoisonBytes = 256;
  /// Binds the buffer to `index` of `target`. A shader storage binding above the device's
  /// GL_MAX_SHADER_STORAGE_BLOCK_SIZE (GL's minimum is 16 MiB; 128 MiB on some GPUs, 2 GiB on
  /// others) is a GpuError naming the buffer and the limit: a shader would read and write past
  /// what the device addresses, a wrong image with no GL error. A buffer whose rounded-up storage
  /// alone passes the limit binds its size() bytes.
  void bindBase(GLenum target, GLuint index) const;

 private:
  detail::ObjectKey key() const {
    return {detail::ObjectKind::Buffer, 0, 0, 0, 0, 0, storage_, flags_};
  }
  std::size_t size_ = 0;     ///< the bytes asked for (size())
  std::size_t storage_ = 0;  ///< the bytes stored: storageFor(size_)
  GLbitfield flags_ = 0;
};

/// GL_MAX_SHADER_STORAGE_BLOCK_SIZE of the device (GL's minimum, 16 MiB, where it reports
/// none): the most bytes one storage buffer binding may hold. Needs the context.
std::size_t maxStorageBlock();
/// Makes maxStorageBlock() at most `bytes` (0: the device's again), so that a test sees a
/// small device's limit (GL's least is 16 MiB; llvmpipe's 128 MiB) at a small scene's sizes.
void setMaxStorageBlockForTesting(std::size_t bytes);

/// One range of a buffer to read back, and where it goes.
struct BufferRange {
  const Buffer* buffer;
  std::size_t offset, bytes;
  void* dst;
};

/// Reads every range back with one host wait: the ranges are copied on the GPU into one staging
/// buffer, which is read once. Inside a RecyclingScope the staging buffer is kept until the
/// scope ends and grown with headroom (Buffer::grownFor), so a frame's statistics read, whose
/// size follows the frame's sample counts, makes no buffer in a steady frame.
void readBuffers(std::span<const BufferRange> ranges);

/// Texture object (glCreateTextures) with immutable storage.
class Texture : public GlObject<TextureDeleter> {
 public:
  /// What a texture holds when it is handed out. A texture, new or recycled, is cleared to zero
  /// unless its maker says the next pass writes every texel (`Overwritten`: an upload, or a
  /// compute pass with one imageStore per texel): on an H200 the clear of a 256³ RGBA32F volume
  /// cost ~5 ms that no timer query saw (docs/RESULTS.md, "GPU frames on an NVIDIA H200").
  /// Under validation (gpu/validate.h) an Overwritten texture starts as NaN, so that a promise
  /// not kept shows in the image.
  enum class Contents { Zeroed, Overwritten };
  Texture() = default;
  /// A 2D texture of `format` (sized internal format).
  static Texture make2D(GLenum format, int w, int h, std::string_view label,
                        Contents contents = Contents::Zeroed);
  /// A 3D texture of `format`, GL_LINEAR filtering, CLAMP_TO_EDGE: lookups at normalised
  /// coordinates (u + 0.5) / dims match Grid3::sampleIndex(u) inside the box.
  static Texture make3D(GLenum format, int w, int h, int d, std::string_view label,
                        Contents contents = Contents::Zeroed);
  /// A 2D array texture of `layers` layers, GL_LINEAR filtering, CLAMP_TO_EDGE.
  static Texture make2DArray(GLenum format, int w, int h, int layers, std::string_view label);
  GLenum target() const { return target_; }
  ~Texture() { release(key_); }
  Texture(Texture&& o) noexcept : GlObject(std::move(o)), target_(o.target_), key_(o.key_) {}
  Texture& operator=(Texture&& o) noexcept {
    GlObject::operator=(std::move(o));
    std::swap(target_, o.target_);
    std::swap(key_, o.key_);
    return *this;
  }

 private:
  /// A texture of `target`, `format` and size (w, h, d): recycled (cleared to zero unless
  /// `contents` is Overwritten) or created with its storage.
  Texture(GLenum target, GLenum format, int w, int h, int d, std::string_view label,
          Contents contents = Contents::Zeroed);
  GLenum target_ = 0;
  detail::ObjectKey key_;
};

/// Framebuffer object.
class Framebuffer : public GlObject<FramebufferDeleter> {
 public:
  Framebuffer() = default;
  explicit Framebuffer(std::string_view label);
  ~Framebuffer() { release({detail::ObjectKind::Framebuffer}); }
  Framebuffer(Framebuffer&&) noexcept = default;
  Framebuffer& operator=(Framebuffer&&) noexcept = default;
};

/// A compiled shader stage; compile errors throw GpuError with `file` and the info log.
class Shader : public GlObject<ShaderDeleter> {
 public:
  Shader() = default;
  Shader(GLenum stage, std::string_view source, std::string_view file);
  /// The names of every `uniform` declared in the source (inside #ifdef'd-out blocks too).
  const std::vector<std::string>& declaredUniforms() const { return declared_; }
  GLenum stage() const { return stage_; }

 private:
  std::vector<std::string> declared_;
  GLenum stage_ = 0;
};

/// The names of the uniforms declared in GLSL `source` ("uniform TYPE NAME" with optional
/// layout and precision; uniform blocks are not plain uniforms). No context.
std::vector<std::string> declaredUniforms(std::string_view source);

/// A linked program; link errors throw GpuError with the files and the info log.
/// Uniform locations are resolved once, when the program is linked (the active uniforms), and
/// checked on every use: uniform(name) of a name that no source of the program declares
/// throws GpuError (a misspelt name never fails silently); a declared uniform the compiler
/// removed (unused in this variant) gives -1, which GL ignores.
class Program : public GlObject<ProgramDeleter> {
 public:
  Program() = default;
  Program(std::initializer_list<const Shader*> shaders, std::string_view label);
  /// Makes the program current (and its workgroup size the one dispatch() counts).
  void use() const;
  /// Location of uniform `name` (no GL call), or -1 for a declared uniform the compiler removed;
  /// throws GpuError when no source declares `name`.
  GLint uniform(std::string_view name) const;
  /// Whether a source of the program declares uniform `name` (for passes shared by programs
  /// that declare different uniforms).
  bool declares(std::string_view name) const;
  /// The program's label (for errors).
  const std::string& label() const;

 private:
  struct Uniforms {
    std::string label;
    std::map<std::string, GLint, std::less<>> active;  ///< name (arrays: without [0]) → location
    std::set<std::string, std::less<>> declared;
    std::int64_t localSize = 0;  ///< invocations per workgroup of a compute program, else 0
  };
  std::shared_ptr<const Uniforms> uniforms_;
};

/// Invocations per workgroup of the program last made current through Program::use (0 for a
/// graphics program): what dispatch() multiplies the workgroups by to count invocations.
std::int64_t currentProgramLocalSize();

/// Query object (timer queries for per-stage GPU times).
class Query : public GlObject<QueryDeleter> {
 public:
  Query() = default;
  Query(GLenum target, std::string_view label);
  ~Query() { release({detail::ObjectKind::Query, target_}); }
  Query(Query&& o) noexcept : GlObject(std::move(o)), target_(o.target_) {}
  Query& operator=(Query&& o) noexcept {
    GlObject::operator=(std::move(o));
    std::swap(target_, o.target_);
    return *this;
  }

 private:
  GLenum target_ = 0;
};

/// Vertex array object; the stages draw attribute-less geometry generated from gl_VertexID and
/// gl_InstanceID, but core profile still needs one bound.
class VertexArray : public GlObject<VertexArrayDeleter> {
 public:
  VertexArray() = default;
  explicit VertexArray(std::string_view label);
  ~VertexArray() { release({detail::ObjectKind::VertexArray}); }
  VertexArray(VertexArray&&) noexcept = default;
  VertexArray& operator=(VertexArray&&) noexcept = default;
};

}  // namespace scatterlab::gpu
