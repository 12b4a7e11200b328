#include "gpu/validate.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <regex>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"

namespace scatterlab::gpu {

namespace {

// ---- What a program reads and writes (from its interface and its GLSL sources) ----

/// How a shader declares a resource (a name declared in several #if branches: the weakest).
struct Qualifiers {
  bool readOnly = true;   ///< every declaration says `readonly`
  bool writeOnly = true;  ///< every declaration says `writeonly`
};

struct BlockUse {
  GLuint binding = 0;
  Qualifiers q;
};

struct OpaqueUse {  ///< an image or sampler uniform (arrays: `count` consecutive locations)
  GLint location = -1;
  GLint count = 1;
  Qualifiers q;             ///< images only
  GLenum bindingQuery = 0;  ///< samplers: GL_TEXTURE_BINDING_* of the unit for its type
};

struct ProgramUse {
  std::vector<BlockUse> storage, uniformBlocks;
  std::vector<OpaqueUse> images, samplers;
};

/// The smallest per-program limits of the desktop GPUs a user may have where they are below
/// llvmpipe's (NVIDIA: 8 image units and image uniforms, llvmpipe 192 and 32; 2 048 uniform
/// components in a compute shader, llvmpipe 16 384): a program above them runs on llvmpipe and
/// fails on the GPU. Storage blocks (16) llvmpipe limits as NVIDIA does.
constexpr GLint kPortableImageUniforms = 8;  ///< GL_MAX_COMPUTE_IMAGE_UNIFORMS, _IMAGE_UNITS
constexpr GLint kPortableSamplers = 16;      ///< the spec's GL_MAX_COMPUTE_TEXTURE_IMAGE_UNITS
constexpr GLint kPortableUniformComponents = 2048;  ///< GL_MAX_COMPUTE_UNIFORM_COMPONENTS

/// Strips // and /* */ comments.
std::string stripComments(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size();) {
    if (s.compare(i, 2, "//") == 0) {
      while (i < s.size() && s[i] != '\n') ++i;
    } else if (s.compare(i, 2, "/*") == 0) {
      const std::size_t e = s.find("*/", i + 2);
      i = e == std::string::npos ? s.size() : e + 2;
      out += ' ';
    } else {
      out += s[i++];
    }
  }
  return out;
}

/// A `#if` expression of the shaders: defined(X), defined X, !, &&, ||, parentheses, integers
/// and macros defined as integers (anything else: 0).
class Condition {
 public:
  Condition(std::string_view text, const std::map<std::string, std::string>& defines)
      : t_(text), d_(defines) {}
  bool value() { return orExpr() != 0; }

 private:
  void space() {
    while (i_ < t_.size() && std::isspace((unsigned char)t_[i_])) ++i_;
  }
  bool eat(std::string_view tok) {
    space();
    if (t_.substr(i_, tok.size()) != tok) return false;
    i_ += tok.size();
    return true;
  }
  std::string word() {
    space();
    const std::size_t b = i_;
    while (i_ < t_.size() && (std::isalnum((unsigned char)t_[i_]) || t_[i_] == '_')) ++i_;
    return std::string(t_.substr(b, i_ - b));
  }
  long orExpr() {
    long v = andExpr();
    while (eat("||")) v = (andExpr() != 0) | (v != 0);
    return v;
  }
  long andExpr() {
    long v = unary();
    while (eat("&&")) v = (unary() != 0) & (v != 0);
    return v;
  }
  long unary() {
    if (eat("!")) return unary() == 0;
    if (eat("(")) {
      const long v = orExpr();
      eat(")");
      return v;
    }
    const std::string w = word();
    if (w == "defined") {
      const bool paren = eat("(");
      const std::string name = word();
      if (paren) eat(")");
      return d_.contains(name);
    }
    if (w.empty()) {
      ++i_;
      return 0;
    }
    if (std::isdigit((unsigned char)w[0])) return std::strtol(w.c_str(), nullptr, 0);
    const auto it = d_.find(w);
    return it == d_.end() ? 0 : std::strtol(it->second.c_str(), nullptr, 0);
  }
  std::string_view t_;
  const std::map<std::string, std::string>& d_;
  std::size_t i_ = 0;
};

/// The lines of `source` the preprocessor keeps (its #define, #undef and conditionals applied;
/// directives themselves dropped).
std::string activeLines(const std::string& source) {
  std::map<std::string, std::string> defines;
  struct Branch {
    bool parentActive, active, taken;
  };
  std::vector<Branch> stack;
  const auto active = [&] { return stack.empty() || stack.back().active; };
  std::string out;
  std::size_t p = 0;
  while (p < source.size()) {
    std::size_t e = source.find('\n', p);
    if (e == std::string::npos) e = source.size();
    std::string line = source.substr(p, e - p);
    p = e + 1;
    while (!line.empty() && line.back() == '\\' && p < source.size()) {  // continued
      line.pop_back();
      e = source.find('\n', p);
      if (e == std::string::npos) e = source.size();
      line += source.substr(p, e - p);
      p = e + 1;
    }
    const std::size_t f = line.find_first_not_of(" \t\r");
    if (f == std::string::npos || line[f] != '#') {
      if (active()) out += line + '\n';
      continue;
    }
    std::string_view rest = std::string_view(line).substr(f + 1);
    while (!rest.empty() && (rest[0] == ' ' || rest[0] == '\t')) rest.remove_prefix(1);
    std::size_t n = 0;
    while (n < rest.size() && std::isalpha((unsigned char)rest[n])) ++n;
    const std::string directive(rest.substr(0, n));
    const std::string_view arg = rest.substr(n);
    const auto firstWord = [&] {
      std::string_view a = arg;
      while (!a.empty() && std::isspace((unsigned char)a[0])) a.remove_prefix(1);
      std::size_t k = 0;
      while (k < a.size() && (std::isalnum((unsigned char)a[k]) || a[k] == '_')) ++k;
      return std::make_pair(std::string(a.substr(0, k)), std::string(a.substr(k)));
    };
    if (directive == "ifdef" || directive == "ifndef" || directive == "if") {
      bool v = false;
      if (directive == "if")
        v = Condition(arg, defines).value();
      else
        v = defines.contains(firstWord().first) == (directive == "ifdef");
      const bool parent = active();
      stack.push_back({parent, parent && v, v});
    } else if (directive == "elif" && !stack.empty()) {
      Branch& b = stack.back();
      const bool v = !b.taken && Condition(arg, defines).value();
      b.active = b.parentActive && v;
      b.taken = b.taken || v;
    } else if (directive == "else" && !stack.empty()) {
      Branch& b = stack.back();
      b.active = b.parentActive && !b.taken;
      b.taken = true;
    } else if (directive == "endif" && !stack.empty()) {
      stack.pop_back();
    } else if (directive == "define" && active()) {
      auto [name, value] = firstWord();
      const std::size_t v = value.find_first_not_of(" \t");
      defines[name] = v == std::string::npos ? "" : value.substr(v);
    } else if (directive == "undef" && active()) {
      defines.erase(firstWord().first);
    }
  }
  return out;
}

/// The qualifiers of every `buffer NAME {` block and `uniform ... imageXX NAME` in `source`.
void parseQualifiers(const std::string& source, std::map<std::string, Qualifiers>& blocks,
                     std::map<std::string, Qualifiers>& images) {
  static const std::regex kBlock(R"(\bbuffer\s+(\w+)\s*$)");
  static const std::regex kImage(R"(\buniform\b[^;]*\b[iu]?image\w+\s+(\w+)\s*(\[[^\]]*\])?\s*$)");
  static const std::regex kRead(R"(\breadonly\b)"), kWrite(R"(\bwriteonly\b)");
  const std::string text = activeLines(stripComments(source));
  std::size_t start = 0;
  for (std::size_t i = 0; i <= text.size(); ++i) {
    if (i < text.size() && text[i] != ';' && text[i] != '{' && text[i] != '}') continue;
    std::string decl = text.substr(start, i - start);
    std::replace(decl.begin(), decl.end(), '\n', ' ');
    start = i + 1;
    std::smatch m;
    std::map<std::string, Qualifiers>* into = nullptr;
    if (std::regex_search(decl, m, kBlock))
      into = &blocks;
    else if (std::regex_search(decl, m, kImage))
      into = &images;
    if (!into) continue;
    Qualifiers& q = (*into)[m[1].str()];
    q.readOnly = q.readOnly && std::regex_search(decl, kRead);
    q.writeOnly = q.writeOnly && std::regex_search(decl, kWrite);
  }
}

bool isImageType(GLenum t) {
  // clang-format off
  static constexpr GLenum kTypes[] = {
      GL_IMAGE_1D, GL_IMAGE_2D, GL_IMAGE_3D, GL_IMAGE_2D_RECT, GL_IMAGE_CUBE, GL_IMAGE_BUFFER,
      GL_IMAGE_1D_ARRAY, GL_IMAGE_2D_ARRAY, GL_IMAGE_CUBE_MAP_ARRAY, GL_IMAGE_2D_MULTISAMPLE,
      GL_IMAGE_2D_MULTISAMPLE_ARRAY, GL_INT_IMAGE_1D, GL_INT_IMAGE_2D, GL_INT_IMAGE_3D,
      GL_INT_IMAGE_2D_RECT, GL_INT_IMAGE_CUBE, GL_INT_IMAGE_BUFFER, GL_INT_IMAGE_1D_ARRAY,
      GL_INT_IMAGE_2D_ARRAY, GL_INT_IMAGE_CUBE_MAP_ARRAY, GL_INT_IMAGE_2D_MULTISAMPLE,
      GL_INT_IMAGE_2D_MULTISAMPLE_ARRAY, GL_UNSIGNED_INT_IMAGE_1D, GL_UNSIGNED_INT_IMAGE_2D,
      GL_UNSIGNED_INT_IMAGE_3D, GL_UNSIGNED_INT_IMAGE_2D_RECT, GL_UNSIGNED_INT_IMAGE_CUBE,
      GL_UNSIGNED_INT_IMAGE_BUFFER, GL_UNSIGNED_INT_IMAGE_1D_ARRAY,
      GL_UNSIGNED_INT_IMAGE_2D_ARRAY, GL_UNSIGNED_INT_IMAGE_CUBE_MAP_ARRAY,
      GL_UNSIGNED_INT_IMAGE_2D_MULTISAMPLE, GL_UNSIGNED_INT_IMAGE_2D_MULTISAMPLE_ARRAY};
  // clang-format on
  return std::ranges::find(kTypes, t) != std::end(kTypes);
}

/// GL_TEXTURE_BINDING_* of a sampler type's target (0: not a sampler).
GLenum samplerBindingQuery(GLenum t) {
  struct Entry {
    GLenum type, query;
  };
  // clang-format off
  static constexpr Entry kSamplers[] = {
      {GL_SAMPLER_2D, GL_TEXTURE_BINDING_2D}, {GL_SAMPLER_2D_SHADOW, GL_TEXTURE_BINDING_2D},
      {GL_INT_SAMPLER_2D, GL_TEXTURE_BINDING_2D}, {GL_UNSIGNED_INT_SAMPLER_2D, GL_TEXTURE_BINDING_2D},
      {GL_SAMPLER_3D, GL_TEXTURE_BINDING_3D}, {GL_INT_SAMPLER_3D, GL_TEXTURE_BINDING_3D},
      {GL_UNSIGNED_INT_SAMPLER_3D, GL_TEXTURE_BINDING_3D},
      {GL_SAMPLER_2D_ARRAY, GL_TEXTURE_BINDING_2D_ARRAY},
      {GL_SAMPLER_2D_ARRAY_SHADOW, GL_TEXTURE_BINDING_2D_ARRAY},
      {GL_INT_SAMPLER_2D_ARRAY, GL_TEXTURE_BINDING_2D_ARRAY},
      {GL_UNSIGNED_INT_SAMPLER_2D_ARRAY, GL_TEXTURE_BINDING_2D_ARRAY},
      {GL_SAMPLER_1D, GL_TEXTURE_BINDING_1D}, {GL_INT_SAMPLER_1D, GL_TEXTURE_BINDING_1D},
      {GL_UNSIGNED_INT_SAMPLER_1D, GL_TEXTURE_BINDING_1D},
      {GL_SAMPLER_CUBE, GL_TEXTURE_BINDING_CUBE_MAP}, {GL_SAMPLER_CUBE_SHADOW, GL_TEXTURE_BINDING_CUBE_MAP},
      {GL_INT_SAMPLER_CUBE, GL_TEXTURE_BINDING_CUBE_MAP},
      {GL_UNSIGNED_INT_SAMPLER_CUBE, GL_TEXTURE_BINDING_CUBE_MAP},
      {GL_SAMPLER_BUFFER, GL_TEXTURE_BINDING_BUFFER}, {GL_INT_SAMPLER_BUFFER, GL_TEXTURE_BINDING_BUFFER},
      {GL_UNSIGNED_INT_SAMPLER_BUFFER, GL_TEXTURE_BINDING_BUFFER}};
  // clang-format on
  for (const Entry& e : kSamplers)
    if (e.type == t) return e.query;
  return 0;
}

std::string resourceName(GLuint program, GLenum iface, GLuint i) {
  char name[256] = {};
  GLsizei len = 0;
  glGetProgramResourceName(program, iface, i, sizeof name, &len, name);
  std::string s(name, std::size_t(len));
  if (s.size() > 3 && s.ends_with("[0]")) s.resize(s.size() - 3);
  return s;
}

ProgramUse describeProgram(GLuint program, const std::vector<std::string>& sources) {
  std::map<std::string, Qualifiers> blockQ, imageQ;
  for (const std::string& s : sources) parseQualifiers(s, blockQ, imageQ);
  ProgramUse use;
  GLint n = 0;
  glGetProgramInterfaceiv(program, GL_SHADER_STORAGE_BLOCK, GL_ACTIVE_RESOURCES, &n);
  for (GLint i = 0; i < n; ++i) {
    const GLenum prop = GL_BUFFER_BINDING;
    GLint binding = 0;
    glGetProgramResourceiv(program, GL_SHADER_STORAGE_BLOCK, GLuint(i), 1, &prop, 1, nullptr,
                           &binding);
    BlockUse b{GLuint(binding), {false, false}};  // not in the sources: read and written
    if (const auto it = blockQ.find(resourceName(program, GL_SHADER_STORAGE_BLOCK, GLuint(i)));
        it != blockQ.end())
      b.q = it->second;
    use.storage.push_back(b);
  }
  glGetProgramInterfaceiv(program, GL_UNIFORM_BLOCK, GL_ACTIVE_RESOURCES, &n);
  for (GLint i = 0; i < n; ++i) {
    const GLenum prop = GL_BUFFER_BINDING;
    GLint binding = 0;
    glGetProgramResourceiv(program, GL_UNIFORM_BLOCK, GLuint(i), 1, &prop, 1, nullptr, &binding);
    use.uniformBlocks.push_back({GLuint(binding), {true, false}});
  }
  glGetProgramInterfaceiv(program, GL_UNIFORM, GL_ACTIVE_RESOURCES, &n);
  for (GLint i = 0; i < n; ++i) {
    const GLenum props[4] = {GL_TYPE, GL_LOCATION, GL_ARRAY_SIZE, GL_BLOCK_INDEX};
    GLint v[4] = {};
    glGetProgramResourceiv(program, GL_UNIFORM, GLuint(i), 4, props, 4, nullptr, v);
    if (v[3] != -1 || v[1] < 0) continue;
    const GLenum type = GLenum(v[0]);
    OpaqueUse o{v[1], std::max(v[2], 1), {false, false}, 0};
    if (isImageType(type)) {
      if (const auto it = imageQ.find(resourceName(program, GL_UNIFORM, GLuint(i)));
          it != imageQ.end())
        o.q = it->second;
      use.images.push_back(o);
    } else if (const GLenum q = samplerBindingQuery(type)) {
      o.bindingQuery = q;
      use.samplers.push_back(o);
    }
  }
  return use;
}

// ---- Shader writes not yet made visible ----

struct Write {
  std::int64_t begin = 0, end = 0;  ///< bytes of a buffer; textures: [0, INT64_MAX)
  GLbitfield pending = 0;           ///< barrier bits not issued since the write
  std::string writer;               ///< the program that wrote
};

enum class Kind : std::uint64_t { Buffer = 1, Texture = 2 };

std::uint64_t key(Kind k, GLuint id) {
  return (std::uint64_t(k) << 32) | id;
}

struct State {
  std::map<GLuint, ProgramUse> programs;
  std::set<GLuint> exemptBuffers;
  std::map<std::uint64_t, std::vector<Write>> writes;
};

std::mutex gMutex;
bool gInstalled = false;
std::map<EGLContext, State> gStates;

State& state() {
  return gStates[eglGetCurrentContext()];
}

std::string objectLabel(GLenum identifier, GLuint id) {
  char buf[256] = {};
  GLsizei len = 0;
  glGetObjectLabel(identifier, id, sizeof buf, &len, buf);
  const std::string name(buf, std::size_t(std::max(len, 0)));
  const char* kind = identifier == GL_BUFFER    ? "buffer"
                     : identifier == GL_TEXTURE ? "texture"
                                                : "program";
  return std::string(kind) + " " + std::to_string(id) + (name.empty() ? "" : " '" + name + "'");
}

std::string currentProgramLabel() {
  GLint p = 0;
  glGetIntegerv(GL_CURRENT_PROGRAM, &p);
  return p ? objectLabel(GL_PROGRAM, GLuint(p)) : std::string("no program");
}

const char* bitName(GLbitfield bit) {
  switch (bit) {
    case GL_SHADER_STORAGE_BARRIER_BIT:
      return "GL_SHADER_STORAGE_BARRIER_BIT";
    case GL_UNIFORM_BARRIER_BIT:
      return "GL_UNIFORM_BARRIER_BIT";
    case GL_SHADER_IMAGE_ACCESS_BARRIER_BIT:
      return "GL_SHADER_IMAGE_ACCESS_BARRIER_BIT";
    case GL_TEXTURE_FETCH_BARRIER_BIT:
      return "GL_TEXTURE_FETCH_BARRIER_BIT";
    case GL_COMMAND_BARRIER_BIT:
      return "GL_COMMAND_BARRIER_BIT";
    case GL_BUFFER_UPDATE_BARRIER_BIT:
      return "GL_BUFFER_UPDATE_BARRIER_BIT";
    case GL_TEXTURE_UPDATE_BARRIER_BIT:
      return "GL_TEXTURE_UPDATE_BARRIER_BIT";
    case GL_FRAMEBUFFER_BARRIER_BIT:
      return "GL_FRAMEBUFFER_BARRIER_BIT";
    default:
      return "a barrier bit";
  }
}

constexpr std::int64_t kWhole = INT64_MAX;

/// Throws when [begin, end) of the object overlaps a write whose `bit` is still pending.
void check(State& s, Kind kind, GLuint id, std::int64_t begin, std::int64_t end, GLbitfield bit,
           std::string_view access) {
  if (!id || (kind == Kind::Buffer && s.exemptBuffers.contains(id))) return;
  const auto it = s.writes.find(key(kind, id));
  if (it == s.writes.end()) return;
  for (const Write& w : it->second)
    if ((w.pending & bit) && w.begin < end && begin < w.end) {
      const std::string what = objectLabel(kind == Kind::Buffer ? GL_BUFFER : GL_TEXTURE, id);
      const std::string range = kind == Kind::Buffer && w.end != kWhole
                                    ? " (bytes " + std::to_string(std::max(w.begin, begin)) + "–" +
                                          std::to_string(std::min(w.end, end)) + ")"
                                    : "";
      throw GpuError("GL hazard (SCATTERLAB_GPU_VALIDATE): " + std::string(access) + " " + what +
                     range + ", written by a shader of " + w.writer + ", with no glMemoryBarrier(" +
                     bitName(bit) + ") since that write");
    }
}

void recordWrite(State& s, Kind kind, GLuint id, std::int64_t begin, std::int64_t end,
                 const std::string& writer) {
  if (id && !(kind == Kind::Buffer && s.exemptBuffers.contains(id)))
    s.writes[key(kind, id)].push_back({begin, end, GL_ALL_BARRIER_BITS, writer});
}

/// A transfer or clear that overwrites [begin, end): the shader writes' bytes in it are gone (a
/// write it overlaps keeps its bytes on either side, so that two transfers side by side, an
/// upload and a clear of the rest, forget a write over both).
void forgetCovered(State& s, Kind kind, GLuint id, std::int64_t begin, std::int64_t end) {
  const auto it = s.writes.find(key(kind, id));
  if (it == s.writes.end()) return;
  std::vector<Write> kept;
  for (Write& w : it->second) {
    if (w.end <= begin || end <= w.begin) {
      kept.push_back(std::move(w));
      continue;
    }
    if (w.begin < begin) kept.push_back({w.begin, begin, w.pending, w.writer});
    if (end < w.end) kept.push_back({end, w.end, w.pending, w.writer});
  }
  it->second = std::move(kept);
  if (it->second.empty()) s.writes.erase(it);
}

std::int64_t bufferSize(GLuint id) {
  GLint64 size = 0;
  glGetNamedBufferParameteri64v(id, GL_BUFFER_SIZE, &size);
  return size;
}

/// The buffer bound at indexed binding `index` of a target and its bytes (the whole buffer where
/// it was bound without a range).
struct BoundRange {
  GLuint buffer = 0;
  std::int64_t begin = 0, end = 0;
};

BoundRange boundRange(GLenum binding, GLenum start, GLenum size, GLuint index) {
  GLint buf = 0;
  GLint64 b = 0, n = 0;
  glGetIntegeri_v(binding, index, &buf);
  if (!buf) return {};
  glGetInteger64i_v(start, index, &b);
  glGetInteger64i_v(size, index, &n);
  return {GLuint(buf), b, n ? b + n : bufferSize(GLuint(buf))};
}

struct PendingWrite {
  Kind kind;
  GLuint id;
  std::int64_t begin, end;
};

/// Checks every resource the current program reads against the writes pending; returns what it
/// will write. `what`: "a dispatch of" / "a draw of".
std::vector<PendingWrite> checkProgramAccesses(State& s, std::string_view what) {
  std::vector<PendingWrite> out;
  GLint program = 0;
  glGetIntegerv(GL_CURRENT_PROGRAM, &program);
  if (!program) return out;
  // A program linked before validation was installed is not known, and not checked.
  const auto found = s.programs.find(GLuint(program));
  if (found == s.programs.end()) return out;
  const ProgramUse& use = found->second;
  const std::string by = std::string(what) + " " + objectLabel(GL_PROGRAM, GLuint(program));
  for (const BlockUse& b : use.storage) {
    const BoundRange r =
        boundRange(GL_SHADER_STORAGE_BUFFER_BINDING, GL_SHADER_STORAGE_BUFFER_START,
                   GL_SHADER_STORAGE_BUFFER_SIZE, b.binding);
    if (!r.buffer) continue;
    if (!b.q.writeOnly)
      check(s, Kind::Buffer, r.buffer, r.begin, r.end, GL_SHADER_STORAGE_BARRIER_BIT,
            by + " reads storage binding " + std::to_string(b.binding) + ":");
    if (!b.q.readOnly) out.push_back({Kind::Buffer, r.buffer, r.begin, r.end});
  }
  for (const BlockUse& b : use.uniformBlocks) {
    const BoundRange r = boundRange(GL_UNIFORM_BUFFER_BINDING, GL_UNIFORM_BUFFER_START,
                                    GL_UNIFORM_BUFFER_SIZE, b.binding);
    if (r.buffer)
      check(s, Kind::Buffer, r.buffer, r.begin, r.end, GL_UNIFORM_BARRIER_BIT,
            by + " reads uniform block binding " + std::to_string(b.binding) + ":");
  }
  for (const OpaqueUse& im : use.images)
    for (GLint k = 0; k < im.count; ++k) {
      GLint unit = 0, tex = 0, access = 0;
      glGetUniformiv(GLuint(program), im.location + k, &unit);
      if (unit >= kPortableImageUniforms)
        throw GpuError("GL portability (SCATTERLAB_GPU_VALIDATE): " + by + " uses image unit " +
                       std::to_string(unit) + "; NVIDIA has " +
                       std::to_string(kPortableImageUniforms) + " (GL_MAX_IMAGE_UNITS)");
      glGetIntegeri_v(GL_IMAGE_BINDING_NAME, GLuint(unit), &tex);
      if (!tex) continue;
      glGetIntegeri_v(GL_IMAGE_BINDING_ACCESS, GLuint(unit), &access);
      if (!im.q.writeOnly && access != GL_WRITE_ONLY)
        check(s, Kind::Texture, GLuint(tex), 0, kWhole, GL_SHADER_IMAGE_ACCESS_BARRIER_BIT,
              by + " reads image unit " + std::to_string(unit) + ":");
      if (!im.q.readOnly && access != GL_READ_ONLY)
        out.push_back({Kind::Texture, GLuint(tex), 0, kWhole});
    }
  if (!use.samplers.empty()) {
    GLint active = 0;
    glGetIntegerv(GL_ACTIVE_TEXTURE, &active);
    for (const OpaqueUse& sm : use.samplers)
      for (GLint k = 0; k < sm.count; ++k) {
        GLint unit = 0, tex = 0;
        glGetUniformiv(GLuint(program), sm.location + k, &unit);
        glActiveTexture(GLenum(GL_TEXTURE0 + unit));
        glGetIntegerv(sm.bindingQuery, &tex);
        check(s, Kind::Texture, GLuint(tex), 0, kWhole, GL_TEXTURE_FETCH_BARRIER_BIT,
              by + " samples texture unit " + std::to_string(unit) + ":");
      }
    glActiveTexture(GLenum(active));
  }
  return out;
}

void recordWrites(State& s, const std::vector<PendingWrite>& writes) {
  if (writes.empty()) return;
  const std::string writer = currentProgramLabel();
  for (const PendingWrite& w : writes) recordWrite(s, w.kind, w.id, w.begin, w.end, writer);
}

/// The draw framebuffer's attachments, checked for GL_FRAMEBUFFER_BARRIER_BIT.
void checkFramebuffer(State& s, std::string_view by) {
  GLint fbo = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &fbo);
  if (!fbo) return;
  GLint maxColor = 0;
  glGetIntegerv(GL_MAX_COLOR_ATTACHMENTS, &maxColor);
  std::vector<GLenum> points{GL_DEPTH_ATTACHMENT, GL_STENCIL_ATTACHMENT};
  for (GLint i = 0; i < maxColor; ++i) points.push_back(GLenum(GL_COLOR_ATTACHMENT0 + i));
  for (GLenum a : points) {
    GLint type = GL_NONE, name = 0;
    glGetNamedFramebufferAttachmentParameteriv(GLuint(fbo), a,
                                               GL_FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE, &type);
    if (type != GL_TEXTURE) continue;
    glGetNamedFramebufferAttachmentParameteriv(GLuint(fbo), a,
                                               GL_FRAMEBUFFER_ATTACHMENT_OBJECT_NAME, &name);
    check(s, Kind::Texture, GLuint(name), 0, kWhole, GL_FRAMEBUFFER_BARRIER_BIT,
          std::string(by) + " renders into");
  }
}

// ---- What every desktop GPU allows ----

/// Components of a default-block uniform of `type` (opaque types: 1).
GLint components(GLenum type) {
  struct Entry {
    GLenum type;
    GLint n;
  };
  // clang-format off
  static constexpr Entry kSizes[] = {
      {GL_FLOAT_VEC2, 2}, {GL_INT_VEC2, 2}, {GL_UNSIGNED_INT_VEC2, 2}, {GL_BOOL_VEC2, 2},
      {GL_DOUBLE, 2}, {GL_FLOAT_VEC3, 3}, {GL_INT_VEC3, 3}, {GL_UNSIGNED_INT_VEC3, 3},
      {GL_BOOL_VEC3, 3}, {GL_FLOAT_VEC4, 4}, {GL_INT_VEC4, 4}, {GL_UNSIGNED_INT_VEC4, 4},
      {GL_BOOL_VEC4, 4}, {GL_FLOAT_MAT2, 4}, {GL_DOUBLE_VEC2, 4}, {GL_DOUBLE_VEC3, 6},
      {GL_DOUBLE_VEC4, 8}, {GL_FLOAT_MAT3, 9}, {GL_FLOAT_MAT4, 16}, {GL_DOUBLE_MAT4, 32}};
  // clang-format on
  for (const Entry& e : kSizes)
    if (e.type == type) return e.n;
  return 1;  // scalars and opaque types
}

void checkPortableLimits(GLuint program, const ProgramUse& use) {
  GLint images = 0, samplers = 0, uniformComponents = 0;
  for (const OpaqueUse& o : use.images) images += o.count;
  for (const OpaqueUse& o : use.samplers) samplers += o.count;
  GLint n = 0;
  glGetProgramInterfaceiv(program, GL_UNIFORM, GL_ACTIVE_RESOURCES, &n);
  for (GLint i = 0; i < n; ++i) {
    const GLenum props[3] = {GL_TYPE, GL_ARRAY_SIZE, GL_BLOCK_INDEX};
    GLint v[3] = {};
    glGetProgramResourceiv(program, GL_UNIFORM, GLuint(i), 3, props, 3, nullptr, v);
    if (v[2] == -1) uniformComponents += components(GLenum(v[0])) * std::max(v[1], 1);
  }
  const auto over = [&](const char* what, GLint count, GLint limit) {
    if (count > limit)
      throw GpuError(
          "GL portability (SCATTERLAB_GPU_VALIDATE): " + objectLabel(GL_PROGRAM, program) +
          " uses " + std::to_string(count) + " " + what + ", above the " + std::to_string(limit) +
          " a desktop GPU may allow (NVIDIA's limit; llvmpipe allows more)");
  };
  over("image uniforms", images, kPortableImageUniforms);
  over("samplers", samplers, kPortableSamplers);
  over("uniform components", uniformComponents, kPortableUniformComponents);
}

// ---- The hooks: each checks, then calls the entry point it replaced ----

struct Real {
  decltype(epoxy_glMemoryBarrier) memoryBarrier;
  decltype(epoxy_glMemoryBarrierByRegion) memoryBarrierByRegion;
  decltype(epoxy_glDispatchCompute) dispatchCompute;
  decltype(epoxy_glDispatchComputeIndirect) dispatchComputeIndirect;
  decltype(epoxy_glDrawArrays) drawArrays;
  decltype(epoxy_glDrawArraysInstanced) drawArraysInstanced;
  decltype(epoxy_glGetNamedBufferSubData) getNamedBufferSubData;
  decltype(epoxy_glCopyNamedBufferSubData) copyNamedBufferSubData;
  decltype(epoxy_glNamedBufferSubData) namedBufferSubData;
  decltype(epoxy_glClearNamedBufferData) clearNamedBufferData;
  decltype(epoxy_glClearNamedBufferSubData) clearNamedBufferSubData;
  decltype(epoxy_glGetTextureImage) getTextureImage;
  decltype(epoxy_glGetTextureSubImage) getTextureSubImage;
  decltype(epoxy_glTextureSubImage2D) textureSubImage2D;
  decltype(epoxy_glTextureSubImage3D) textureSubImage3D;
  decltype(epoxy_glClearTexImage) clearTexImage;
  decltype(epoxy_glDeleteBuffers) deleteBuffers;
  decltype(epoxy_glDeleteTextures) deleteTextures;
  decltype(epoxy_glLinkProgram) linkProgram;
  decltype(epoxy_glDeleteProgram) deleteProgram;
} real;

/// A barrier of `bits`: the writes' pending bits cleared, writes with none left forgotten.
void clearPending(GLbitfield bits) {
  std::lock_guard lock(gMutex);
  State& s = state();
  for (auto it = s.writes.begin(); it != s.writes.end();) {
    for (Write& w : it->second) w.pending &= ~bits;
    std::erase_if(it->second, [](const Write& w) { return w.pending == 0; });
    it = it->second.empty() ? s.writes.erase(it) : std::next(it);
  }
}

void memoryBarrier(GLbitfield bits) {
  clearPending(bits);
  real.memoryBarrier(bits);
}

void memoryBarrierByRegion(GLbitfield bits) {
  clearPending(bits);
  real.memoryBarrierByRegion(bits);
}

/// A dispatch or draw: `checkFirst` (its indirect sizes, its framebuffer) and the current
/// program's reads checked, the call made (without the lock: it may be long on a driver that
/// runs it at once), then the program's writes recorded.
template <class CheckFirst, class Call>
void checkedCall(const char* what, CheckFirst checkFirst, Call call) {
  std::unique_lock lock(gMutex);
  State& s = state();
  checkFirst(s);
  const std::vector<PendingWrite> writes = checkProgramAccesses(s, what);
  lock.unlock();
  call();
  lock.lock();
  recordWrites(state(), writes);
}

void dispatchCompute(GLuint x, GLuint y, GLuint z) {
  checkedCall(
      "a dispatch of", [](State&) {}, [&] { real.dispatchCompute(x, y, z); });
}

void dispatchComputeIndirect(GLintptr offset) {
  checkedCall(
      "a dispatch of",
      [&](State& s) {
        GLint indirect = 0;
        glGetIntegerv(GL_DISPATCH_INDIRECT_BUFFER_BINDING, &indirect);
        check(s, Kind::Buffer, GLuint(indirect), offset, offset + 3 * sizeof(GLuint),
              GL_COMMAND_BARRIER_BIT,
              "an indirect dispatch of " + currentProgramLabel() + " takes its size from");
      },
      [&] { real.dispatchComputeIndirect(offset); });
}

void checkDrawFramebuffer(State& s) {
  checkFramebuffer(s, "a draw of " + currentProgramLabel());
}

void drawArrays(GLenum mode, GLint first, GLsizei count) {
  checkedCall("a draw of", checkDrawFramebuffer, [&] { real.drawArrays(mode, first, count); });
}

void drawArraysInstanced(GLenum mode, GLint first, GLsizei count, GLsizei instances) {
  checkedCall("a draw of", checkDrawFramebuffer,
              [&] { real.drawArraysInstanced(mode, first, count, instances); });
}

void bufferAccess(GLuint id, std::int64_t begin, std::int64_t end, std::string_view access,
                  bool overwrites) {
  std::lock_guard lock(gMutex);
  State& s = state();
  check(s, Kind::Buffer, id, begin, end, GL_BUFFER_UPDATE_BARRIER_BIT, access);
  if (overwrites) forgetCovered(s, Kind::Buffer, id, begin, end);
}

void textureAccess(GLuint id, std::string_view access, bool overwritesAll) {
  std::lock_guard lock(gMutex);
  State& s = state();
  check(s, Kind::Texture, id, 0, kWhole, GL_TEXTURE_UPDATE_BARRIER_BIT, access);
  if (overwritesAll) forgetCovered(s, Kind::Texture, id, 0, kWhole);
}

void getNamedBufferSubData(GLuint b, GLintptr offset, GLsizeiptr n, void* data) {
  bufferAccess(b, offset, offset + n, "a read-back of", false);
  real.getNamedBufferSubData(b, offset, n, data);
}

void copyNamedBufferSubData(GLuint from, GLuint to, GLintptr ro, GLintptr wo, GLsizeiptr n) {
  bufferAccess(from, ro, ro + n, "a buffer copy from", false);
  bufferAccess(to, wo, wo + n, "a buffer copy into", true);
  real.copyNamedBufferSubData(from, to, ro, wo, n);
}

void namedBufferSubData(GLuint b, GLintptr offset, GLsizeiptr n, const void* data) {
  bufferAccess(b, offset, offset + n, "an upload into", true);
  real.namedBufferSubData(b, offset, n, data);
}

void clearNamedBufferData(GLuint b, GLenum internal, GLenum format, GLenum type, const void* data) {
  bufferAccess(b, 0, kWhole, "a clear of", true);
  real.clearNamedBufferData(b, internal, format, type, data);
}

void clearNamedBufferSubData(GLuint b, GLenum internal, GLintptr offset, GLsizeiptr n,
                             GLenum format, GLenum type, const void* data) {
  bufferAccess(b, offset, offset + n, "a clear of", true);
  real.clearNamedBufferSubData(b, internal, offset, n, format, type, data);
}

void getTextureImage(GLuint t, GLint level, GLenum format, GLenum type, GLsizei n, void* px) {
  textureAccess(t, "a read-back of", false);
  real.getTextureImage(t, level, format, type, n, px);
}

void getTextureSubImage(GLuint t, GLint level, GLint x, GLint y, GLint z, GLsizei w, GLsizei h,
                        GLsizei d, GLenum format, GLenum type, GLsizei n, void* px) {
  textureAccess(t, "a read-back of", false);
  real.getTextureSubImage(t, level, x, y, z, w, h, d, format, type, n, px);
}

void textureSubImage2D(GLuint t, GLint level, GLint x, GLint y, GLsizei w, GLsizei h, GLenum format,
                       GLenum type, const void* px) {
  textureAccess(t, "an upload into", false);
  real.textureSubImage2D(t, level, x, y, w, h, format, type, px);
}

void textureSubImage3D(GLuint t, GLint level, GLint x, GLint y, GLint z, GLsizei w, GLsizei h,
                       GLsizei d, GLenum format, GLenum type, const void* px) {
  textureAccess(t, "an upload into", false);
  real.textureSubImage3D(t, level, x, y, z, w, h, d, format, type, px);
}

void clearTexImage(GLuint t, GLint level, GLenum format, GLenum type, const void* data) {
  textureAccess(t, "a clear of", true);
  real.clearTexImage(t, level, format, type, data);
}

void deleteBuffers(GLsizei n, const GLuint* ids) {
  {
    std::lock_guard lock(gMutex);
    State& s = state();
    for (GLsizei i = 0; i < n; ++i) s.writes.erase(key(Kind::Buffer, ids[i]));
  }
  real.deleteBuffers(n, ids);
}

void deleteTextures(GLsizei n, const GLuint* ids) {
  {
    std::lock_guard lock(gMutex);
    State& s = state();
    for (GLsizei i = 0; i < n; ++i) s.writes.erase(key(Kind::Texture, ids[i]));
  }
  real.deleteTextures(n, ids);
}

void linkProgram(GLuint program) {
  real.linkProgram(program);
  std::vector<std::string> sources;
  GLint count = 0;
  glGetProgramiv(program, GL_ATTACHED_SHADERS, &count);
  std::vector<GLuint> shaders(std::size_t(std::max(count, 0)));
  if (count > 0) glGetAttachedShaders(program, count, nullptr, shaders.data());
  for (GLuint sh : shaders) {
    GLint len = 0;
    glGetShaderiv(sh, GL_SHADER_SOURCE_LENGTH, &len);
    std::string src(std::size_t(std::max(len, 1)), '\0');
    GLsizei got = 0;
    glGetShaderSource(sh, GLsizei(src.size()), &got, src.data());
    src.resize(std::size_t(got));
    sources.push_back(std::move(src));
  }
  GLint linked = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &linked);
  std::lock_guard lock(gMutex);
  State& s = state();
  s.programs.erase(program);
  if (!linked) return;
  const ProgramUse& use =
      s.programs.emplace(program, describeProgram(program, sources)).first->second;
  checkPortableLimits(program, use);
}

void deleteProgram(GLuint program) {
  {
    std::lock_guard lock(gMutex);
    state().programs.erase(program);
  }
  real.deleteProgram(program);
}

template <class F>
void hook(F& slot, F& saved, F replacement, const char* name) {
  saved = reinterpret_cast<F>(eglGetProcAddress(name));
  if (!saved) throw GpuError(std::string("GL validation: cannot resolve ") + name);
  slot = replacement;
}

}  // namespace

bool validationRequested() {
  const char* v = std::getenv("SCATTERLAB_GPU_VALIDATE");
  return v && *v && std::strcmp(v, "0") != 0;
}

void exemptFromValidation(unsigned id) {
  // Recorded before validation is installed too: a test that installs it later in the process
  // (GpuValidate) must not see the loop guard's atomics of later passes as hazards.
  std::lock_guard lock(gMutex);
  state().exemptBuffers.insert(GLuint(id));
}

bool validating() {
  std::lock_guard lock(gMutex);
  return gInstalled;
}

void installValidation() {
  std::lock_guard lock(gMutex);
  if (gInstalled) return;
// Each entry point and the hook of the same name (real.<member> keeps the driver's).
#define SCATTERLAB_HOOK(gl, member) hook(epoxy_##gl, real.member, &member, #gl)
  SCATTERLAB_HOOK(glMemoryBarrier, memoryBarrier);
  SCATTERLAB_HOOK(glMemoryBarrierByRegion, memoryBarrierByRegion);
  SCATTERLAB_HOOK(glDispatchCompute, dispatchCompute);
  SCATTERLAB_HOOK(glDispatchComputeIndirect, dispatchComputeIndirect);
  SCATTERLAB_HOOK(glDrawArrays, drawArrays);
  SCATTERLAB_HOOK(glDrawArraysInstanced, drawArraysInstanced);
  SCATTERLAB_HOOK(glGetNamedBufferSubData, getNamedBufferSubData);
  SCATTERLAB_HOOK(glCopyNamedBufferSubData, copyNamedBufferSubData);
  SCATTERLAB_HOOK(glNamedBufferSubData, namedBufferSubData);
  SCATTERLAB_HOOK(glClearNamedBufferData, clearNamedBufferData);
  SCATTERLAB_HOOK(glClearNamedBufferSubData, clearNamedBufferSubData);
  SCATTERLAB_HOOK(glGetTextureImage, getTextureImage);
  SCATTERLAB_HOOK(glGetTextureSubImage, getTextureSubImage);
  SCATTERLAB_HOOK(glTextureSubImage2D, textureSubImage2D);
  SCATTERLAB_HOOK(glTextureSubImage3D, textureSubImage3D);
  SCATTERLAB_HOOK(glClearTexImage, clearTexImage);
  SCATTERLAB_HOOK(glDeleteBuffers, deleteBuffers);
  SCATTERLAB_HOOK(glDeleteTextures, deleteTextures);
  SCATTERLAB_HOOK(glLinkProgram, linkProgram);
  SCATTERLAB_HOOK(glDeleteProgram, deleteProgram);
#undef SCATTERLAB_HOOK
  gInstalled = true;
}

}  // namespace scatterlab::gpu
