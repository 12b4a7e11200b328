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
#include <vector>

#include "core/stages.h"
#include "cpu/fused_volume.h"
#include "shading/transport.h"
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

/// The lights of the factored march (the volume holds V = S / A): A(x, ω) of LightFactor
/// (shading/transport.h) with the same terms, laid out for the kernels, which evaluate the point
/// and spot lights SIMD over a group of steps (cpu/fused_march_impl.h, factorGroup) instead of
/// light by light and step by step. Directional lights give the same A all along a view ray
/// (ω is the ray's, the irradiance constant): directional() sums them once per ray.
struct FusedFactor;

class FusedLights {
 public:
  /// `lamp`: LampModel's m_l (off: every m = 1), as LightFactor's.
  /// `glow`: render.glow (false: every glow's reach 0, no substeps).
  FusedLights(const Scene& scene, const LampModel& lamp, bool glow = true);
  /// A of the directional lights towards `toViewer`.
  Vec3 directional(const Vec3& toViewer) const;
  /// Point or spot light j at the step of length dt centred at ray parameter t of `f`: where the
  /// step passes through its glow (core/stages.h, glowSubsteps > 1) its term of A averaged over
  /// the substeps' midpoints into `out` (factorGroup's formula, LightFactor::overStep's rule),
  /// and true; false elsewhere. Out of line, in a file built for the baseline instruction set:
  /// the kernels are built for SSE2 and for AVX2, and an inline function both define (this one,
  /// or glowSubsteps and the vector maths it calls) could be linked from the AVX2 build into
  /// every caller.
  bool glowMean(int j, const FusedFactor& f, float t, float dt, float out[3]) const;
  /// A's far field (render.far_field; FarField in shading/transport.h), as LightFactor's
  /// setFarField: a point light beyond 2R of every step of a group is not evaluated, one within
  /// is weighted by 1 − w (FarField::weight), and farLookup adds the grid's part. Null: every
  /// light exact. The grid must outlive this object.
  void setFarField(const FarField* far);
  /// The far field's part at world point (x, y, z) into `out` (FarField::lookup). Out of line,
  /// as glowMean.
  void farLookup(float x, float y, float z, float out[3]) const;
  /// The lights FusedFactor::near lists for the steps of `f`'s ray between ray parameters ta
  /// and tb (with the far field on): the spot lights, and the point lights whose distance to
  /// the segment is below 2R (plus a margin for rounding), into `out`.
  void nearSpan(const FusedFactor& f, float ta, float tb, std::vector<int>& out) const;

  int count = 0;  ///< point and spot lights, in the scene's order
  /// Per point or spot light: position, intensity (RGB), spot axis and smoothstep edges
  /// (cosOuter, cosInner; a point light: edges −2, −1, so its falloff is 1 everywhere), and
  /// LampModel's k (0: m = 1).
  std::vector<float> px, py, pz, ir, ig, ib, ax, ay, az, e0, e1, k;
  /// Per point or spot light: kGlowRatio / w, its glow's substep scale (core/stages.h).
  std::vector<float> glow;
  bool hg = false;  ///< Henyey–Greenstein (else isotropic, kInvFourPi)
  float g = 0.0f;
  float farRadius = 0.0f;  ///< the far field's R in world units (setFarField); 0: none
  /// The far field's grid as the kernels read it (setFarField; FarField's members): RGB floats
  /// per vertex, x fastest, and null where the grid's float offsets do not fit 32 bits (the
  /// kernels then call farLookup per step).
  const float* farA = nullptr;
  int farDims[3] = {0, 0, 0};
  float farLo[3] = {0.0f, 0.0f, 0.0f}, farCell[3] = {1.0f, 1.0f, 1.0f};

 private:
  const FarField* far_ = nullptr;
  std::vector<Light> directional_;
  Phase phase_;
};

/// The factor of one view ray (the volume holds V = S / A): `lights` at its steps, step i at
/// world point origin + (t0 + (i + ½)·dt)·dir (FusedRay's t0, dt), seen along toViewer = −dir,
/// plus `constant`, A of the directional lights along this ray. The kernels multiply S of the
/// steps that contribute (D > 0, S ≠ 0) by A there, before the group's exp.
struct FusedFactor {
  const FusedLights* lights;
  float origin[3], dir[3], toViewer[3];
  float constant[3];
  /// With a far field (FusedLights::farRadius > 0): the point and spot lights that can be
  /// within 2R of a step of this span (FusedLights::nearSpan), `nearCount` of them; the kernels
  /// evaluate only these. nearCount −1: every light.
  const int* near = nullptr;
  int nearCount = -1;
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
