// The AVX2 instantiation of the gather's row loop (cpu/gather_rows_impl.h); this file alone
// is compiled with -mavx2 -ffast-math (cpu/CMakeLists.txt), called only where the CPU has AVX2.
#include "cpu/gather_rows_impl.h"

namespace scatterlab::gather_detail {

void rowAvx2(float* __restrict r0, float* __restrict g0, float* __restrict b0, float* __restrict w0,
             int i0, int i1, float lox, float hx, float px, float c, float R, float eps, Vec3 base,
             Vec3 gx, const float* __restrict occ, float lo, float hi, bool bounded) {
  if (bounded) {
    if (occ)
      row<true, true>(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, occ, lo, hi);
    else
      row<false, true>(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, nullptr, lo, hi);
  } else if (occ) {
    row<true, false>(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, occ, 0.0f, 0.0f);
  } else {
    row<false, false>(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, nullptr, 0.0f,
                      0.0f);
  }
}

void normaliseAvx2(const float* __restrict r, const float* __restrict g, const float* __restrict b,
                   const float* __restrict w, int i0, int i1, float* __restrict qr,
                   float* __restrict qg, float* __restrict qb) {
  normalise(r, g, b, w, i0, i1, qr, qg, qb);
}

}  // namespace scatterlab::gather_detail
