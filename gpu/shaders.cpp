#include "gpu/shaders.h"

#include <map>

#include "core/error.h"
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

const Program& cachedProgram(const std::string& key, const std::function<Program()>& make) {
  static auto* cache = new std::map<std::string, Program>();  // leaked on purpose, see header
  auto it = cache->find(key);
  if (it == cache->end()) it = cache->emplace(key, make()).first;
  return it->second;
}

}  // namespace scatterlab::gpu
