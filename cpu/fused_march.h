#pragma once
/// The fast march's inner loop over a FusedVolume (issue 14), one run of non-empty steps of one
/// view ray at a time, compiled twice and chosen at run time (render.march_simd):
///  * sse2 (cpu/fused_march_sse2.cpp, the build's baseline x86-64): per step eight 4-float
///    corner loads and seven 4-wide lerps (xsimd), exp of four steps at once;
///  * avx2 (cpu/fused_march_avx2.cpp, built with -mavx2 -mfma -mf16c, used where the CPU
///    has AVX2, FMA and F16C): a cell's two x neighbours (D, S) are contiguous, so a lookup is
///    four 8-float loads (or four 8-half loads widened by F16C), lerped along y and z as 8-wide
///    batches and along x once; exp of eight steps at once (xsimd).
/// Both sum the steps in the plain march's order: L += T·Ω·(1 − a)·S, wt += T·(1 − a)·t,
/// T *= a per step with D > 0, stopping once T <= minT.

#include <string>

#include "core/stages.h"
#include "cpu/fused_volume.h"
#include "shading/view_march.h"

namespace scatterlab {

/// One view ray in the volume's index space: step i is at u0 + i·du, ray distance t0 + (i + ½)·dt.
struct FusedRay {
  float u0[3], du[3];
  float t0, dt;
};
struct FusedMarchConstants {
  float sigmaT, ratio, minT;  ///< σt, Ω = σs/σt, the march's min_transmittance
};
/// The ray's running sums.
struct FusedMarchState {
  float L[3];
  float T;
  float wt;  ///< Σ T·(1 − a)·t (the depth's numerator)
};

/// The lights' factor of the factored march (the volume holds V = S / A, shading/transport.h):
/// `scale(ctx, i, count, V)` multiplies S = (V[q][1], V[q][2], V[q][3]) of steps i, …,
/// i + count − 1 of the ray by A at their points; only steps with D = V[q][0] > 0 and S ≠ 0
/// need it (the others add nothing). Called once per group of steps, before their exp.
struct FusedFactor {
  void (*scale)(const void* ctx, int i, int count, float (*V)[4]);
  const void* ctx;
};

/// Marches steps [i, end) of `ray`; `factor`: null, or the lights' factor to multiply S by.
using FusedSpanKernel = void (*)(const FusedVolumeView& v, const FusedMarchConstants& c,
                                 const FusedRay& ray, int i, int end, FusedMarchState& s,
                                 const FusedFactor* factor);

/// Whether this CPU runs the avx2 kernel (AVX2, FMA and F16C).
bool cpuHasAvx2Kernel();
/// The kernel for `simd` (Auto: avx2 where the CPU has it). Throws ConfigError naming
/// render.march_simd when avx2 is asked for and the CPU lacks it.
FusedSpanKernel fusedSpanKernel(MarchSimd simd);
/// "sse2" or "avx2": the kernel fusedSpanKernel(simd) returns.
std::string fusedKernelName(MarchSimd simd);

namespace detail {
void fusedSpanSse2(const FusedVolumeView&, const FusedMarchConstants&, const FusedRay&, int, int,
                   FusedMarchState&, const FusedFactor*);
void fusedSpanAvx2(const FusedVolumeView&, const FusedMarchConstants&, const FusedRay&, int, int,
                   FusedMarchState&, const FusedFactor*);
}  // namespace detail

}  // namespace scatterlab
