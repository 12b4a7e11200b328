#pragma once
/// The built-in methods, each registered once (methods/register.cpp: one table row per method
/// names its stages; the backends it runs on follow from the stage variants registered).

#include <vector>

#include "methods/settings.h"

namespace scatterlab {

/// The descriptions of the built-in methods, in the order of the table.
const std::vector<MethodDesc>& builtinMethods();

/// Registers every built-in method in methods(). Call after the stage variants are registered
/// (registerIntegrators(), registerReconstructions(), ..., gpu::registerGpuStages()).
void registerMethods();

}  // namespace scatterlab
