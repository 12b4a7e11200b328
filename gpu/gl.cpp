#include "gpu/gl.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <functional>
#include <limits>
#include <regex>
#include <string>
#include <vector>

#include <unistd.h>

#include "core/error.h"
#include "gpu/context.h"
#include "gpu/validate.h"

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
  if (name.empty()) return;
  // A label of GL_MAX_LABEL_LENGTH or more characters is GL_INVALID_VALUE: keep its start.
  static const GLsizei maxLength = [] {
    GLint n = 0;
    glGetIntegerv(GL_MAX_LABEL_LENGTH, &n);
    return GLsizei(n);
  }();
  const GLsizei n = std::min(GLsizei(name.size()), maxLength > 0 ? maxLength - 1 : 0);
  glObjectLabel(identifier, id, n, name.data());
}

/// The recycler's state. GL is single-threaded here (gpu/context.h), so no locking.
struct Recycler {
  int scopes = 0;
  std::size_t freeBytes = 0;
  std::deque<std::pair<detail::ObjectKey, GLuint>> free;  ///< oldest first
  GlObjectCounts counts;
  /// readBuffers' staging buffer, kept while a scope is open (a name and its storage in bytes;
  /// not in `free`: no other request takes it).
  GLuint staging = 0;
  std::size_t stagingBytes = 0;
};

Recycler& recycler() {
  static Recycler r;
  return r;
}

/// Most objects and bytes the free list keeps; the oldest are deleted beyond either.
constexpr std::size_t kMaxFree = 256;
constexpr std::size_t kMaxFreeBytes = std::size_t(1) << 30;

/// The storage an object of `key` holds (textures: 16 bytes a texel at most; estimated).
std::size_t storageBytes(const detail::ObjectKey& key) {
  if (key.kind == detail::ObjectKind::Buffer) return key.bytes;
  if (key.kind != detail::ObjectKind::Texture) return 0;
  std::size_t texel = 16;
  if (key.format == GL_R32F || key.format == GL_DEPTH_COMPONENT32F) texel = 4;
  if (key.format == GL_RG32F) texel = 8;
  return std::size_t(key.w) * std::size_t(key.h) * std::size_t(key.d) * texel;
}

void deleteObject(const detail::ObjectKey& key, GLuint id) {
  switch (key.kind) {
    case detail::ObjectKind::Buffer:
      glDeleteBuffers(1, &id);
      break;
    case detail::ObjectKind::Texture:
      glDeleteTextures(1, &id);
      break;
    case detail::ObjectKind::Framebuffer:
      glDeleteFramebuffers(1, &id);
      break;
    case detail::ObjectKind::Query:
      glDeleteQueries(1, &id);
      break;
    case detail::ObjectKind::VertexArray:
    case detail::ObjectKind::None:
      glDeleteVertexArrays(1, &id);
      break;
  }
}

bool isDepthFormat(GLenum format) {
  return format == GL_DEPTH_COMPONENT32F || format == GL_DEPTH_COMPONENT24 ||
         format == GL_DEPTH_COMPONENT16 || format == GL_DEPTH_COMPONENT32;
}

}  // namespace

GlObjectCounts glObjectCounts() {
  GlObjectCounts c = recycler().counts;
  c.free = (long long)recycler().free.size();
  return c;
}

RecyclingScope::RecyclingScope() {
  ++recycler().scopes;
}

RecyclingScope::~RecyclingScope() {
  Recycler& r = recycler();
  if (--r.scopes > 0) return;
  // Without a current context the names are left to the driver (see GlObject's destructor).
  if (detail::contextCurrent()) {
    for (const auto& [key, id] : r.free) deleteObject(key, id);
    if (r.staging) glDeleteBuffers(1, &r.staging);
  }
  if (r.staging) --r.counts.live;
  r.free.clear();
  r.freeBytes = 0;
  r.staging = 0;
  r.stagingBytes = 0;
}

namespace detail {

bool contextCurrent() {
  return glContextCurrent();
}

GLuint takeRecycled(const ObjectKey& key) {
  Recycler& r = recycler();
  if (r.scopes == 0) return 0;
  for (auto it = r.free.begin(); it != r.free.end(); ++it)
    if (it->first == key) {
      const GLuint id = it->second;
      r.freeBytes -= storageBytes(it->first);
      r.free.erase(it);
      ++r.counts.reused;
      ++r.counts.live;
      return id;
    }
  return 0;
}

bool recycle(const ObjectKey& key, GLuint id) {
  Recycler& r = recycler();
  if (r.scopes == 0) return false;
  r.free.emplace_back(key, id);
  r.freeBytes += storageBytes(key);
  --r.counts.live;
  while (r.free.size() > kMaxFree || (r.freeBytes > kMaxFreeBytes && r.free.size() > 1)) {
    r.freeBytes -= storageBytes(r.free.front().first);
    deleteObject(r.free.front().first, r.free.front().second);
    r.free.pop_front();
  }
  return true;
}

void countCreated() {
  ++recycler().counts.created;
  ++recycler().counts.live;
}

void countDeleted() {
  --recycler().counts.live;
}

}  // namespace detail

namespace {
HostWaitCounts waitCounts;
}

HostWaitCounts hostWaitCounts() {
  return waitCounts;
}

void countHostWait(std::string_view what) {
  ++waitCounts.waits;
  static const bool trace = [] {
    const char* v = std::getenv("SCATTERLAB_TRACE_WAITS");
    return v && *v && std::string_view(v) != "0";
  }();
  if (trace) std::fprintf(stderr, "scatterlab: host wait: %.*s\n", int(what.size()), what.data());
}

void countImageReadback(double ms) {
  ++waitCounts.imageReadbacks;
  waitCounts.imageReadbackMs += ms;
}

void checkGl(std::string_view pass) {
  std::string errors;
  for (int i = 0; i < 16; ++i) {
    const GLenum e = glGetError();
    if (e == GL_NO_ERROR) break;
    errors += (errors.empty() ? "" : ", ") + std::string(glErrorName(e));
  }
  if (!errors.empty()) throw GpuError("OpenGL error after " + std::string(pass) + ": " + errors);
}

std::size_t Buffer::storageFor(std::size_t bytes) {
  // Zero-sized storage is an error in GL; keep one word so empty sets still bind.
  if (bytes < 4) return 4;
  if (bytes <= 256) return bytes;
  std::size_t p = 128;
  while (p * 2 < bytes) p *= 2;  // p < bytes <= 2p
  const std::size_t step = p <= (std::size_t(1) << 20) ? p / 4 : p / 8;
  return (bytes + step - 1) / step * step;
}

std::size_t Buffer::grownFor(std::size_t bytes) {
  const std::size_t grown = bytes + bytes / 4, limit = maxStorageBlock();
  return bytes <= limit ? std::min(grown, limit) : grown;
}

Buffer::Buffer(std::size_t bytes, const void* data, GLbitfield flags, std::string_view name)
    : size_(bytes), storage_(storageFor(bytes)), flags_(flags | GL_DYNAMIC_STORAGE_BIT) {
  const std::size_t poison = validating() ? kPoisonBytes : 0;
  id_ = detail::takeRecycled(key());
  if (id_) {
    // A recycled buffer is cleared where no data is given (its bytes past size() as well).
    if (bytes && data)
      glNamedBufferSubData(id_, 0, GLsizeiptr(bytes), data);
    else
      glClearNamedBufferData(id_, GL_R8, GL_RED, GL_UNSIGNED_BYTE, nullptr);
  } else {
    glCreateBuffers(1, &id_);
    detail::countCreated();
    const std::size_t gl = storage_ + poison;
    const bool whole = bytes && data && gl == bytes;
    glNamedBufferStorage(id_, GLsizeiptr(gl), whole ? data : nullptr, flags_);
    if (bytes && data && !whole) glNamedBufferSubData(id_, 0, GLsizeiptr(bytes), data);
    // New storage is undefined in GL (zeros on llvmpipe, not on every GPU): cleared as a
    // recycled buffer is.
    if (!data) glClearNamedBufferData(id_, GL_R8, GL_RED, GL_UNSIGNED_BYTE, nullptr);
  }
  if (poison) {
    const GLubyte ff = 0xff;
    glClearNamedBufferSubData(id_, GL_R8UI, GLintptr(bytes), GLsizeiptr(storage_ + poison - bytes),
                              GL_RED_INTEGER, GL_UNSIGNED_BYTE, &ff);
  }
  label(GL_BUFFER, id_, name);
}

bool Buffer::extendTo(std::size_t bytes) {
  if (!id_ || bytes > storage_) return false;
  if (bytes > size_ && validating())  // poisoned past size(): given back as 0 (kPoisonBytes)
    glClearNamedBufferSubData(id_, GL_R8UI, GLintptr(size_), GLsizeiptr(bytes - size_),
                              GL_RED_INTEGER, GL_UNSIGNED_BYTE, nullptr);
  size_ = std::max(size_, bytes);
  return true;
}

void Buffer::bindBase(GLenum target, GLuint index) const {
  if (target == GL_SHADER_STORAGE_BUFFER) {
    const std::size_t limit = maxStorageBlock();
    if (size_ > limit) {
      char name[256] = {};
      GLsizei n = 0;
      glGetObjectLabel(GL_BUFFER, id_, GLsizei(sizeof name), &n, name);
      throw GpuError("'" + std::string(name, std::size_t(n)) + "': a storage buffer of " +
                     std::to_string((size_ + (1u << 20) - 1) >> 20) +
                     " MiB is above what this device's shaders address in one block "
                     "(GL_MAX_SHADER_STORAGE_BLOCK_SIZE: " +
                     std::to_string(limit >> 20) +
                     " MiB); use fewer samples, a coarser volume or the CPU backend");
    }
    if (storage_ > limit) {
      glBindBufferRange(target, index, id_, 0, GLsizeiptr(size_));
      return;
    }
  }
  glBindBufferBase(target, index, id_);
}

void Buffer::read(void* dst, std::size_t n, std::size_t offset) const {
  if (!n) return;
  countHostWait("buffer read-back");
  // Every shader write before the read-back is in what it reads (gpu/validate.h).
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glGetNamedBufferSubData(id_, GLintptr(offset), GLsizeiptr(n), dst);
}

namespace {
std::size_t forcedStorageBlock = 0;  ///< setMaxStorageBlockForTesting
}  // namespace

std::size_t maxStorageBlock() {
  static const std::size_t limit = [] {
    GLint64 v = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &v);
    return v > 0 ? std::size_t(v) : std::size_t(1) << 24;  // GL's minimum
  }();
  return forcedStorageBlock ? std::min(limit, forcedStorageBlock) : limit;
}

void setMaxStorageBlockForTesting(std::size_t bytes) {
  forcedStorageBlock = bytes;
}

void readBuffers(std::span<const BufferRange> ranges) {
  std::size_t total = 0;
  for (const BufferRange& r : ranges) total += r.bytes;
  if (total == 0) return;
  if (ranges.size() == 1) return ranges[0].buffer->read(ranges[0].dst, total, ranges[0].offset);
  // The staging buffer: the scope's kept one (grown with headroom when too small), or one for
  // this call outside every scope.
  Recycler& rec = recycler();
  Buffer temporary;
  GLuint staging = 0;
  if (rec.scopes > 0) {
    if (rec.stagingBytes < total) {
      if (rec.staging) {
        glDeleteBuffers(1, &rec.staging);
        detail::countDeleted();
      }
      rec.stagingBytes = Buffer::grownFor(total);
      glCreateBuffers(1, &rec.staging);
      detail::countCreated();
      glNamedBufferStorage(rec.staging, GLsizeiptr(rec.stagingBytes), nullptr, 0);
      label(GL_BUFFER, rec.staging, "read-back staging");
    }
    staging = rec.staging;
  } else {
    temporary = Buffer(total, nullptr, 0, "read-back staging");
    staging = temporary.id();
  }
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);  // the copies see every shader write before
  std::size_t at = 0;
  for (const BufferRange& r : ranges) {
    if (r.bytes)
      glCopyNamedBufferSubData(r.buffer->id(), staging, GLintptr(r.offset), GLintptr(at),
                               GLsizeiptr(r.bytes));
    at += r.bytes;
  }
  std::vector<unsigned char> bytes(total);
  countHostWait("buffer read-back");
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glGetNamedBufferSubData(staging, 0, GLsizeiptr(total), bytes.data());
  at = 0;
  for (const BufferRange& r : ranges) {
    if (r.bytes) std::memcpy(r.dst, bytes.data() + at, r.bytes);
    at += r.bytes;
  }
}

namespace {

std::size_t bytesPerTexel(GLenum format) {
  switch (format) {
    case GL_RGBA32F:
      return 16;
    case GL_RG32F:
      return 8;
    case GL_R16F:
      return 2;
    case GL_RGBA16F:
      return 8;
    default:
      return 4;  // R32F, R32UI, DEPTH_COMPONENT32F, ...
  }
}

/// The texture `name` (w × h × d texels of `format`) as a GpuError: what was asked and what the
/// device allows, before anything is allocated.
[[noreturn]] void textureTooLarge(std::string_view name, int w, int h, int d, GLenum format,
                                  const std::string& why) {
  const std::size_t bytes =
      std::size_t(w) * std::size_t(h) * std::size_t(d) * bytesPerTexel(format);
  throw GpuError("'" + std::string(name) + "': a " + std::to_string(w) + " x " + std::to_string(h) +
                 (d > 1 ? " x " + std::to_string(d) : std::string()) + " texture (" +
                 std::to_string((bytes + (1u << 20) - 1) >> 20) + " MiB) " + why);
}

/// Throws when a texture of that size cannot exist on this device (GL's per-target limits).
void checkTextureSize(GLenum target, GLenum format, int w, int h, int d, std::string_view name) {
  GLint maxSize = 0, maxLayers = 0;
  const GLenum limit = target == GL_TEXTURE_3D ? GL_MAX_3D_TEXTURE_SIZE : GL_MAX_TEXTURE_SIZE;
  glGetIntegerv(limit, &maxSize);
  if (target == GL_TEXTURE_2D_ARRAY) glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &maxLayers);
  const int largest = std::max(w, std::max(h, target == GL_TEXTURE_3D ? d : 1));
  if (maxSize > 0 && largest > maxSize)
    textureTooLarge(name, w, h, target == GL_TEXTURE_2D ? 1 : d, format,
                    "exceeds the device's " +
                        std::string(target == GL_TEXTURE_3D ? "GL_MAX_3D_TEXTURE_SIZE"
                                                            : "GL_MAX_TEXTURE_SIZE") +
                        " of " + std::to_string(maxSize) + " per side");
  if (maxLayers > 0 && d > maxLayers)
    textureTooLarge(
        name, w, h, d, format,
        "exceeds the device's GL_MAX_ARRAY_TEXTURE_LAYERS of " + std::to_string(maxLayers));
}

}  // namespace

Texture::Texture(GLenum target, GLenum format, int w, int h, int d, std::string_view name,
                 Contents contents)
    : target_(target), key_{detail::ObjectKind::Texture, target, format, w, h, d} {
  checkTextureSize(target, format, w, h, d, name);
  id_ = detail::takeRecycled(key_);
  if (!id_) {
    glCreateTextures(target, 1, &id_);
    detail::countCreated();
    if (target == GL_TEXTURE_2D)
      glTextureStorage2D(id_, 1, format, w, h);
    else
      glTextureStorage3D(id_, 1, format, w, h, d);
    // A GL_OUT_OF_MEMORY here is reported by the pass's checkGl, naming the pass.
  }
  // A texture's contents are undefined in GL, new or recycled (zeros on llvmpipe, not on every
  // GPU): zeroed unless every texel is about to be written. Under validation (gpu/validate.h)
  // a texture said to be overwritten starts as NaN (depth: 1), so that a texel left unwritten
  // shows in the image on llvmpipe too.
  const GLenum clearFormat = isDepthFormat(format) ? GL_DEPTH_COMPONENT : GL_RED;
  if (contents == Contents::Zeroed) {
    glClearTexImage(id_, 0, clearFormat, GL_FLOAT, nullptr);
  } else if (validating()) {
    const float poison = isDepthFormat(format) ? 1.0f : std::numeric_limits<float>::quiet_NaN();
    glClearTexImage(id_, 0, clearFormat, GL_FLOAT, &poison);
  }
  label(GL_TEXTURE, id_, name);
}

Texture Texture::make2D(GLenum format, int w, int h, std::string_view name, Contents contents) {
  Texture t(GL_TEXTURE_2D, format, w, h, 1, name, contents);
  glTextureParameteri(t.id_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(t.id_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  return t;
}

Texture Texture::make3D(GLenum format, int w, int h, int d, std::string_view name,
                        Contents contents) {
  Texture t(GL_TEXTURE_3D, format, w, h, d, name, contents);
  glTextureParameteri(t.id_, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(t.id_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
    glTextureParameteri(t.id_, wrap, GL_CLAMP_TO_EDGE);
  return t;
}

Texture Texture::make2DArray(GLenum format, int w, int h, int layers, std::string_view name) {
  Texture t(GL_TEXTURE_2D_ARRAY, format, w, h, layers, name);
  glTextureParameteri(t.id_, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(t.id_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T})
    glTextureParameteri(t.id_, wrap, GL_CLAMP_TO_EDGE);
  return t;
}

Framebuffer::Framebuffer(std::string_view name) {
  id_ = detail::takeRecycled({detail::ObjectKind::Framebuffer});
  if (id_) {
    // As new: no attachments, draw buffer 0.
    GLint colors = 8;
    glGetIntegerv(GL_MAX_COLOR_ATTACHMENTS, &colors);
    for (GLint c = 0; c < colors; ++c)
      glNamedFramebufferTexture(id_, GLenum(GL_COLOR_ATTACHMENT0 + c), 0, 0);
    glNamedFramebufferTexture(id_, GL_DEPTH_ATTACHMENT, 0, 0);
    glNamedFramebufferTexture(id_, GL_STENCIL_ATTACHMENT, 0, 0);
    glNamedFramebufferDrawBuffer(id_, GL_COLOR_ATTACHMENT0);
    glNamedFramebufferReadBuffer(id_, GL_COLOR_ATTACHMENT0);
  } else {
    glCreateFramebuffers(1, &id_);
    detail::countCreated();
  }
  label(GL_FRAMEBUFFER, id_, name);
}

namespace {

/// SCATTERLAB_GPU_SHADER_DUMP=DIR: every shader that compiles is written to DIR as
/// <hash of its text>.<comp|vert|frag> (each text once; written under a temporary name and
/// renamed, so tests running side by side never leave half a file), for a compiler other than
/// the driver's to check (scripts/check-shaders.sh: the Khronos reference front end).
void dumpShader(GLenum stage, std::string_view source) {
  static const std::string dir = [] {
    const char* v = std::getenv("SCATTERLAB_GPU_SHADER_DUMP");
    return std::string(v ? v : "");
  }();
  if (dir.empty()) return;
  const char* ext = stage == GL_COMPUTE_SHADER  ? "comp"
                    : stage == GL_VERTEX_SHADER ? "vert"
                                                : "frag";
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016zx", std::hash<std::string_view>()(source));
  const std::string path = dir + "/" + hash + "." + ext;
  const std::string tmp = path + ".tmp" + std::to_string(getpid());
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw GpuError("SCATTERLAB_GPU_SHADER_DUMP: cannot write " + tmp);
  const bool written = std::fwrite(source.data(), 1, source.size(), f) == source.size();
  if (std::fclose(f) != 0 || !written || std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw GpuError("SCATTERLAB_GPU_SHADER_DUMP: cannot write " + path);
  }
}

}  // namespace

Shader::Shader(GLenum stage, std::string_view source, std::string_view file) : stage_(stage) {
  id_ = glCreateShader(stage);
  detail::countCreated();
  const char* src = source.data();
  const GLint len = GLint(source.size());
  glShaderSource(id_, 1, &src, &len);
  glCompileShader(id_);
  GLint ok = 0;
  glGetShaderiv(id_, GL_COMPILE_STATUS, &ok);
  GLint n = 0;
  glGetShaderiv(id_, GL_INFO_LOG_LENGTH, &n);
  std::string log(size_t(std::max(n, 1)), '\0');
  if (n > 1) glGetShaderInfoLog(id_, n, nullptr, log.data());
  log.resize(std::strlen(log.c_str()));
  if (!ok) throw GpuError("shader " + std::string(file) + " failed to compile:\n" + log);
  // Under validation a warning is an error: Mesa's front end warns of a variable read before
  // anything is written to it ("used uninitialized"), which llvmpipe reads as 0 and a GPU as
  // whatever its register held.
  if (validating() && log.find("warning") != std::string::npos)
    throw GpuError("shader " + std::string(file) +
                   " compiled with a warning (SCATTERLAB_GPU_VALIDATE):\n" + log);
  dumpShader(stage, source);
  label(GL_SHADER, id_, file);
  declared_ = gpu::declaredUniforms(source);
}

std::vector<std::string> declaredUniforms(std::string_view source) {
  // "uniform" as a whole word, optional precision, a type, then the name (arrays: name[N]).
  static const std::regex decl(
      R"((?:^|[^\w])uniform\s+(?:(?:lowp|mediump|highp)\s+)?[A-Za-z_]\w*\s+([A-Za-z_]\w*)\s*[\[;=])");
  std::vector<std::string> names;
  const std::string text(source);
  for (auto it = std::sregex_iterator(text.begin(), text.end(), decl); it != std::sregex_iterator();
       ++it)
    names.push_back((*it)[1].str());
  return names;
}

Program::Program(std::initializer_list<const Shader*> shaders, std::string_view name) {
  id_ = glCreateProgram();
  detail::countCreated();
  gpu::label(GL_PROGRAM, id_, name);  // before linking: validation's errors name it
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
  auto u = std::make_shared<Uniforms>();
  u->label = std::string(name);
  for (const Shader* s : shaders)
    for (const std::string& d : s->declaredUniforms()) u->declared.insert(d);
  GLint count = 0;
  glGetProgramInterfaceiv(id_, GL_UNIFORM, GL_ACTIVE_RESOURCES, &count);
  GLint maxLen = 0;
  glGetProgramInterfaceiv(id_, GL_UNIFORM, GL_MAX_NAME_LENGTH, &maxLen);
  std::string buf(std::size_t(std::max(maxLen, 1)), '\0');
  for (GLint i = 0; i < count; ++i) {
    const GLenum prop = GL_LOCATION;
    GLint location = -1;
    glGetProgramResourceiv(id_, GL_UNIFORM, GLuint(i), 1, &prop, 1, nullptr, &location);
    if (location < 0) continue;  // a member of a uniform or storage block
    GLsizei len = 0;
    glGetProgramResourceName(id_, GL_UNIFORM, GLuint(i), GLsizei(buf.size()), &len, buf.data());
    std::string n(buf.data(), std::size_t(len));
    if (n.size() > 3 && n.ends_with("[0]")) n.resize(n.size() - 3);
    u->active.emplace(std::move(n), location);
  }
  for (const Shader* s : shaders)
    if (s->stage() == GL_COMPUTE_SHADER) {
      GLint size[3] = {0, 0, 0};
      glGetProgramiv(id_, GL_COMPUTE_WORK_GROUP_SIZE, size);
      u->localSize = std::int64_t(size[0]) * size[1] * size[2];
    }
  uniforms_ = std::move(u);
}

namespace {
std::int64_t currentLocalSize = 0;  // of the program last made current by Program::use
}  // namespace

void Program::use() const {
  glUseProgram(id_);
  currentLocalSize = uniforms_ ? uniforms_->localSize : 0;
}

std::int64_t currentProgramLocalSize() {
  return currentLocalSize;
}

GLint Program::uniform(std::string_view name) const {
  if (!uniforms_) throw GpuError("uniform '" + std::string(name) + "' of an empty program");
  if (const auto it = uniforms_->active.find(name); it != uniforms_->active.end())
    return it->second;
  if (uniforms_->declared.count(name)) return -1;
  throw GpuError("program '" + uniforms_->label + "' has no uniform '" + std::string(name) +
                 "' (a name no source of it declares)");
}

bool Program::declares(std::string_view name) const {
  return uniforms_ && uniforms_->declared.count(name);
}

const std::string& Program::label() const {
  static const std::string none;
  return uniforms_ ? uniforms_->label : none;
}

Query::Query(GLenum target, std::string_view name) : target_(target) {
  id_ = detail::takeRecycled({detail::ObjectKind::Query, target});
  if (!id_) {
    glCreateQueries(target, 1, &id_);
    detail::countCreated();
  }
  label(GL_QUERY, id_, name);
}

VertexArray::VertexArray(std::string_view name) {
  id_ = detail::takeRecycled({detail::ObjectKind::VertexArray});
  if (!id_) {
    glCreateVertexArrays(1, &id_);
    detail::countCreated();
  }
  label(GL_VERTEX_ARRAY, id_, name);
}

}  // namespace scatterlab::gpu
