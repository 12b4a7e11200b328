#pragma once
/// The one Method class of the volume pipelines: it runs a MethodDesc's stage sequence on one
/// backend — density -> [sampler -> evaluator | refiner] -> [reconstruction] -> integrator —
/// with the stage variants of that backend, and writes the same stats from one place whichever
/// backend ran.

#include <memory>

#include "core/method.h"
#include "methods/settings.h"
#include "sampling/dynamic_sampling.h"

namespace scatterlab {

/// Reads the keys of `desc`'s stages from the render object (the same on every backend), then
/// builds the stage variants of `backend` (which must have them all: a ConfigError names the
/// stage otherwise). `backendNote` (why "auto" chose this backend) goes into the stats.
std::unique_ptr<Method> makePipelineMethod(const MethodDesc& desc, Params& render,
                                           const Scene& scene, Backend backend,
                                           std::string backendNote);

/// Whether every stage `desc` names by default has a variant on `backend`.
bool pipelineRunsOn(const MethodDesc& desc, Backend backend);

}  // namespace scatterlab
