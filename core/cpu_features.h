#pragma once
/// The CPU's instruction-set extensions that the run-time-dispatched SIMD kernels need (the
/// build targets baseline x86-64; AVX2 kernels live in their own files, compiled with -mavx2 and
/// chosen at run time: cpu/fused_march.h, cpu/shadow_rays.h, cpu/gather_rows.h).
/// Queried once (cpuid); all false off x86.

namespace scatterlab {

struct CpuFeatures {
  bool avx2 = false, fma = false, f16c = false;
};

const CpuFeatures& cpuFeatures();

}  // namespace scatterlab
