#pragma once
/// The sample-based CPU methods `gradient`, `rbf` and `nearest` (paper Sec. 4): density
/// volume -> sampler -> radiance evaluator ("volume-tracer") -> reconstruction of the same name
/// -> the CPU ray marcher shared with `per-voxel`. Render object:
///   {"method": "gradient", "sampler": {"type": "gaussian-centres" | "jittered" | "grid",
///    "count": 512, ...}, "delta1": Δ1, "delta2": Δ2, "march_step": ..., "min_transmittance":
///    ..., "radiance_resolution": ...}
/// Without "sampler": gaussian-centres when the medium has Gaussians, else jittered with 512.
/// Stats: samples, uncovered_voxels, timings density, sampling, evaluation, reconstruction,
/// march.

#include <memory>
#include <string>

#include "core/method.h"
#include "core/params.h"
#include "core/stages.h"

namespace scatterlab {

/// The render.sampler object (default: Gaussian centres when the medium has Gaussians, else
/// 512 jittered samples); `type` receives the sampler's name. Shared with the GPU methods.
std::unique_ptr<Sampler> makeSampler(Params& render, const Scene& scene, std::string& type);

/// Registers the three methods in methods(). Needs registerSamplers(),
/// registerRadianceEvaluators() and registerReconstructions() to have run before rendering.
void registerSampledMethods();

}  // namespace scatterlab
