#pragma once
/// GL validation for what a software rasteriser forgives and a GPU does not: memory hazards
/// between passes (docs/gpu.md, "Validation").
///
/// llvmpipe runs every dispatch to its end before the next one starts, so a pass that reads what
/// the pass before it wrote without a glMemoryBarrier of the right bit gets the right data there,
/// and the wrong data, some of the time, on a GPU that overlaps passes and caches incoherent
/// writes. With validation on, every compute dispatch, draw, buffer and texture transfer of the
/// process is checked against the shader writes not yet made visible to it (the GL 4.6 spec,
/// §7.13.2, glMemoryBarrier): a read (or a read-write) of a buffer range, image or texture that a
/// shader wrote, with no barrier of the bit that access needs since that write, throws GpuError
/// naming both programs, the object's label and the bit missing. Writes are tracked per buffer
/// range (the binding's) and per texture; `readonly`/`writeonly` qualifiers are read from the
/// program's GLSL sources, image accesses also from their binding.
///
/// Turned on by the environment variable SCATTERLAB_GPU_VALIDATE (any value but "" and "0") when
/// the context is made; every test executable runs with it (tests/CMakeLists.txt). It hooks
/// libepoxy's entry points, so it also sees the GL calls of code outside gpu/ (tests, an engine
/// on the same thread). It costs a few state queries per call: a debugging and test tool, off in
/// benchmarks.

namespace scatterlab::gpu {

/// Installs the hooks for the process (idempotent); needs a current context. Throws GpuError when
/// an entry point cannot be resolved. Programs linked before are not checked (their sources are
/// gone): gpu::context() installs it before any, when SCATTERLAB_GPU_VALIDATE asks.
void installValidation();

/// Leaves buffer `id` of the current context out of the checks: for a buffer that shaders reach
/// only through atomics whose order does not matter and that the host reads after its own
/// barrier (the loop guard of gpu/shaders.cpp). Recorded also while validation is off, so that
/// installing it later in the process leaves the buffer out as well.
void exemptFromValidation(unsigned id);

/// Whether validation is on in this process.
bool validating();

/// Whether SCATTERLAB_GPU_VALIDATE asks for it.
bool validationRequested();

}  // namespace scatterlab::gpu
