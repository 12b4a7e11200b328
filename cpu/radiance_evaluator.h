#pragma once
/// CPU radiance evaluator "volume-tracer" (paper Sec. 4): S(x_j) by volume tracing towards
/// every light with step Δ1 (render.delta1), ∇S(x_j) by central differences with step Δ2
/// (render.delta2) along world X, Y, Z. TBB-parallel over samples; no GL context.

#include "core/stages.h"

namespace scatterlab {

/// Smallest V whose logarithm the samples hold (ln 1e-9 ≈ −20.7: transmittance below it is
/// black at any exposure).

/// Fills S (and dS when `gradients`) of every sample. The view direction at a point p is
/// towards scene.camera.position from p itself, also at the six offset points, so ∇S is the
/// gradient of the same field the per-voxel baseline traces (this matters only for HG phase).
void evaluateSamples(const Scene& scene, const DensityGrid& density, TracerSteps steps,
                     std::span<RadianceSample> samples, bool gradients);

/// Registers the CPU variant of "volume-tracer" in radianceEvaluators() (delta1, delta2 from
/// the pipeline settings).
void registerRadianceEvaluators();

}  // namespace scatterlab
