#pragma once
/// Shaders embedded at build time from gpu/shaders/*.glsl (gpu/embed_shaders.cmake), and
/// programs built from them. A program's source is "#version 450 core", then the binding
/// points of gpu/bindings.h as #defines (BINDING_LIGHTS 0, ...), then the physics constants
/// shared with the CPU (kSharedConstants of core/stages.h: SL_MIN_V, ...), then the variant's
/// #defines, then the listed files in order, each preceded by `#line 1 <index>` so that the info
/// log's "index:line" points into the right file; a failure throws GpuError naming the files and
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

/// Compiles one stage from embedded `files` with `defines` ("NAME" or "NAME VALUE"); `label`
/// names the program in a loop guard's report (default: the files). Needs a current context.
Shader compileShader(GLenum stage, const std::vector<std::string>& files,
                     const std::vector<std::string>& defines, std::string_view label = {});

/// How many loop iterations in all the driver lets one shader invocation run (0: no cap). Mesa's
/// llvmpipe ends every loop of an invocation after 65 535 iterations together (gallivm's
/// LP_MAX_TGSI_LOOP_ITERATIONS) and the shader runs on with what it has: a view march of
/// march_step 2e-5 came back 88 % dark with no error (issue 37). Measured once per process by a
/// probe (one invocation counting to 2^20), not assumed from the renderer's name. Where there is
/// a cap, every compute and fragment stage is built with a guard that records a program whose
/// invocation reached it (loopGuardCut()). Needs a current context.
int loopIterationLimit();
/// How many dispatches a pass whose invocations evaluate every light splits `lights` lights over
/// (dispatch c of n takes lights c, c + n, c + 2n, …: sourceRadiancePart's and
/// lightFactorStepPart's first and stride, common.glsl), each adding its part to what the
/// dispatches before it stored: froxel's and jittered-march's passes, the factored view march. 1
/// where loops are not capped (NVIDIA, AMD). Where they are (llvmpipe), the fewest that keep an
/// invocation's worst case under half the cap: `steps` steps, each evaluating `perLight` loop
/// iterations per light of its part, and one of its own. The parts add up to every light's term
/// in another order than one pass sums them (the image moves by float rounding, ~1e-7
/// relative); a single light whose own work passes the cap is still the loop guard's GpuError.
int lightDispatches(int lights, double steps, double perLight);
/// Makes lightDispatches return min(`parts`, lights) on any driver (0: back to the cap's), so
/// that a test takes the split path where nothing caps loops or a scene is small.
void setLightDispatchesForTesting(int parts);
/// Clears the guard's record (at the start of each render). Nothing where there is no cap.
void resetLoopGuard();
/// The label of a program an invocation of which reached the loop cap since the last reset
/// ("" when none did, or there is no cap). Reads 4 bytes back where there is a cap.
std::string loopGuardCut();
/// Under validation (gpu/validate.h) where the driver caps loops (llvmpipe: the guard's buffer
/// is there), the label of a program that fetched a texel outside its texture's level since the
/// last reset (texelFetch is checked in every guarded stage); "" when none did.
std::string fetchOutside();

/// SCATTERLAB_GPU_IMPRECISE=N (0 … 1024; unset or 0: off): every stage is compiled with the
/// results of exp, exp2, log, log2, pow, sqrt, inversesqrt, sin, cos, normalize and length moved
/// by ±N units in the last place — what a GPU's approximate built-ins do (NVIDIA's are a few
/// ulps off, more for pow and for exp of a large argument) where llvmpipe's are correctly rounded
/// or nearly so. A test whose CPU ≡ GPU tolerance holds with N = 4 does not depend on llvmpipe's
/// precision; one that fails shows a tolerance borrowed from llvmpipe or a result that jumps at a
/// rounding (scripts/test-imprecise.sh). Throws GpuError naming the variable when it is not a
/// number in range. No context.
int impreciseUlps();
/// The GLSL that does it for `ulps` (> 0), put after the #defines of every stage: slImprecise()
/// and the built-ins as macros around themselves. No context.
std::string imprecisePrologue(int ulps);

/// A compute program from embedded files. Needs a current context.
Program computeProgram(const std::vector<std::string>& files,
                       const std::vector<std::string>& defines, std::string_view label);

/// A vertex + fragment program. Needs a current context.
Program graphicsProgram(const std::vector<std::string>& vertexFiles,
                        const std::vector<std::string>& fragmentFiles,
                        const std::vector<std::string>& defines, std::string_view label);

/// The #define line of every shared constant ("SL_MIN_V 1e-09", as GLSL float literals that
/// read back as the C++ float exactly). No context.
std::vector<std::string> sharedConstantDefines();

/// A program variant: the embedded files of its stages and its #defines. They are its identity:
/// the cache key is made from them, so two passes asking for the same files and defines share
/// one program, and no key can disagree with what was compiled.
struct ProgramVariant {
  std::vector<std::string> compute{};   ///< a compute program's files, or
  std::vector<std::string> vertex{};    ///< a graphics program's vertex stage
  std::vector<std::string> fragment{};  ///< and fragment stage
  std::vector<std::string> defines{};   ///< "NAME" or "NAME VALUE", in order
  /// Appends `d` to the defines when `on`.
  ProgramVariant& define(std::string d, bool on = true) {
    if (on) defines.push_back(std::move(d));
    return *this;
  }
  /// Puts `file` before the other files of the compute stage, or else of the fragment stage
  /// (a library of the stage that traces, such as shadow.glsl).
  ProgramVariant& prepend(const std::string& file);
  std::string key() const;
};

/// The program of `variant`, built once per process (`label` names it in errors and
/// debuggers: its first use's label, with the defines). The context lives until exit, and so
/// do the programs (deliberately never deleted, so that no GL call runs during static
/// destruction). Needs a current context.
const Program& program(const ProgramVariant& variant, std::string_view label);

/// How many programs program() has built (each variant once).
std::size_t programsBuilt();

}  // namespace scatterlab::gpu
