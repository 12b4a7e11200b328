#pragma once
/// Shaders embedded at build time from gpu/shaders/*.glsl (gpu/embed_shaders.cmake), and
/// programs built from them. A program's source is "#version 450 core", then the binding
/// points of gpu/bindings.h as #defines (BINDING_LIGHTS 0, ...), then the variant's #defines,
/// then the listed files in order, each preceded by `#line 1 <index>` so that the info log's
/// "index:line" points into the right file; a failure throws GpuError naming the files and
/// quoting the log.

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "gpu/gl.h"

namespace scatterlab::gpu {

struct EmbeddedShader {
  const char* name;    ///< file name under gpu/shaders
  const char* source;  ///< its text
};

/// Every embedded file (generated table). No GL context needed.
const std::vector<EmbeddedShader>& embeddedShaders();

/// The text of gpu/shaders/`file`; throws GpuError when there is no such file. No context.
std::string_view shaderSource(std::string_view file);

/// Compiles one stage from embedded `files` with `defines` ("NAME" or "NAME VALUE").
/// Needs a current context.
Shader compileShader(GLenum stage, const std::vector<std::string>& files,
                     const std::vector<std::string>& defines);

/// A compute program from embedded files. Needs a current context.
Program computeProgram(const std::vector<std::string>& files,
                       const std::vector<std::string>& defines, std::string_view label);

/// A vertex + fragment program. Needs a current context.
Program graphicsProgram(const std::vector<std::string>& vertexFiles,
                        const std::vector<std::string>& fragmentFiles,
                        const std::vector<std::string>& defines, std::string_view label);

/// The program built by `make` under `key`, built once per process: the context lives until
/// exit, and so do its programs (deliberately never deleted, so that no GL call runs during
/// static destruction). Needs a current context.
const Program& cachedProgram(const std::string& key, const std::function<Program()>& make);

}  // namespace scatterlab::gpu
