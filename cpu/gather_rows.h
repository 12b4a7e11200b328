#pragma once
/// The innermost loop of the Eq. 4 gather (cpu/interpolation.cpp), in its own translation
/// unit so that it alone is compiled with -ffast-math (see CMakeLists.txt): GCC then
/// vectorises it with a reciprocal square root plus one Newton step instead of sqrt + divide.
/// The body is written for that: only finite values (d² is clamped away from 0), no
/// infinity or NaN tests, no reductions across voxels (so no reassociation of sums).

#include "core/math.h"

namespace scatterlab {

/// Whether the row functions below run their AVX2 instantiation (8 lanes; the default where
/// the CPU has AVX2) or the baseline one (4 lanes): turns it on (where available) or off and
/// returns the previous state. For tests and benchmarks; not thread-safe.
bool setGatherRowsAvx2(bool on);

/// Adds sample j's Eq. 4 terms to voxels i0..i1 of one row: voxel i at x = lox + (i + 1/2)·hx;
/// px = x_j; c = dy² + dz² of the row; base = S_j + dy·∂S/∂y + dz·∂S/∂z; gx = ∂S/∂x; R = R_j.
/// W = R / max(‖x − x_j‖, eps·R) where ‖x − x_j‖ < R, else 0. Accumulates W·Taylor into
/// r0/g0/b0 and W into w0.
void gradientRow(float* __restrict r0, float* __restrict g0, float* __restrict b0,
                 float* __restrict w0, int i0, int i1, float lox, float hx, float px, float c,
                 float R, float eps, Vec3 base, Vec3 gx);

/// gradientRow with each voxel's weight W also multiplied by occ[i] (occlusion-aware weights).
void gradientRowWeighted(float* __restrict r0, float* __restrict g0, float* __restrict b0,
                         float* __restrict w0, int i0, int i1, float lox, float hx, float px,
                         float c, float R, float eps, Vec3 base, Vec3 gx,
                         const float* __restrict occ);

/// The bounded Taylor term (PipelineSettings::boundedTaylor): gradientRow / gradientRowWeighted
/// with each sample's estimate clamped to [lo, hi] per channel before it is weighted, so that
/// one sample's extrapolation cannot leave the range the interpolated quantity is known to lie
/// in (V in [0, 1], ln V <= 0). `occ` may be null (all weights 1).
void gradientRowBounded(float* __restrict r0, float* __restrict g0, float* __restrict b0,
                        float* __restrict w0, int i0, int i1, float lox, float hx, float px,
                        float c, float R, float eps, Vec3 base, Vec3 gx,
                        const float* __restrict occ, float lo, float hi);

/// Voxels i0..i1 of one row: q = max(0, a / w) per channel where w > 0 (Eq. 4's division
/// and the clamp to S >= 0), q = max(0, a) elsewhere (the caller ignores those). Compiled with
/// -ffast-math, so GCC multiplies by 1/w instead of dividing three times (within an ulp of
/// the division; volumes 6e-8, images 4.7e-8 relative L2 from the division, fig3 rbf).
void normaliseSpan(const float* __restrict r, const float* __restrict g, const float* __restrict b,
                   const float* __restrict w, int i0, int i1, float* __restrict qr,
                   float* __restrict qg, float* __restrict qb);

}  // namespace scatterlab
