#include "gpu/shaders.h"

#include <cstdio>
#include <map>

#include "core/error.h"
#include "core/stages.h"
#include "gpu/bindings.h"

namespace scatterlab::gpu {

std::string_view shaderSource(std::string_view file) {
  for (const EmbeddedShader& s : embeddedShaders())
    if (file == s.name) return s.source;
  std::string known;
  for (const EmbeddedShader& s : embeddedShaders())
    known += (known.empty() ? "" : ", ") + std::string(s.name);
  throw GpuError("no embedded shader '" + std::string(file) + "'; embedded: " + known);
}

Shader compileShader(GLenum stage, const std::vector<std::string>& files,
                     const std::vector<std::string>& defines) {
  std::string src = "#version 450 core\n";
  for (const BindingDefine& b : kBindingDefines)
    src += "#define " + std::string(b.name) + " " + std::to_string(b.value) + "\n";
  for (const std::string& c : sharedConstantDefines()) src += "#define " + c + "\n";
  for (const std::string& d : defines) src += "#define " + d + "\n";
  std::string names;
  for (size_t i = 0; i < files.size(); ++i) {
    src += "#line 1 " + std::to_string(i + 1) + "\n";
    src += shaderSource(files[i]);
    src += "\n";
    names += (i ? " + " : "") + files[i];
  }
  if (files.size() > 1) {
    names += " (log lines are 'file-index:line' with ";
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
  const Shader cs = compileShader(GL_COMPUTE_SHADER, files, defines);
  return Program({&cs}, label);
}

Program graphicsProgram(const std::vector<std::string>& vertexFiles,
                        const std::vector<std::string>& fragmentFiles,
                        const std::vector<std::string>& defines, std::string_view label) {
  const Shader vs = compileShader(GL_VERTEX_SHADER, vertexFiles, defines);
  const Shader fs = compileShader(GL_FRAGMENT_SHADER, fragmentFiles, defines);
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
