#include "cpu/gather_rows.h"

#include "core/cpu_features.h"
#include "cpu/gather_rows_impl.h"

namespace scatterlab {

using gather_detail::row;

namespace gather_detail {
#ifdef SCATTERLAB_GATHER_AVX2
void rowAvx2(float* __restrict r0, float* __restrict g0, float* __restrict b0, float* __restrict w0,
             int i0, int i1, float lox, float hx, float px, float c, float R, float eps, Vec3 base,
             Vec3 gx, const float* __restrict occ, float lo, float hi, bool bounded);
void normaliseAvx2(const float* __restrict r, const float* __restrict g, const float* __restrict b,
                   const float* __restrict w, int i0, int i1, float* __restrict qr,
                   float* __restrict qg, float* __restrict qb);
#endif
}  // namespace gather_detail

namespace {

/// Whether the rows run the AVX2 instantiation (same operations, 8 lanes instead of 4).
bool useAvx2() {
#ifdef SCATTERLAB_GATHER_AVX2
  return cpuFeatures().avx2;
#else
  return false;
#endif
}
bool kAvx2 = useAvx2();

}  // namespace

bool setGatherRowsAvx2(bool on) {
  const bool was = kAvx2;
  kAvx2 = on && useAvx2();
  return was;
}

void gradientRow(float* __restrict r0, float* __restrict g0, float* __restrict b0,
                 float* __restrict w0, int i0, int i1, float lox, float hx, float px, float c,
                 float R, float eps, Vec3 base, Vec3 gx) {
#ifdef SCATTERLAB_GATHER_AVX2
  if (kAvx2)
    return gather_detail::rowAvx2(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, nullptr,
                                  0.0f, 0.0f, false);
#endif
  row<false, false>(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, nullptr, 0.0f, 0.0f);
}

void gradientRowWeighted(float* __restrict r0, float* __restrict g0, float* __restrict b0,
                         float* __restrict w0, int i0, int i1, float lox, float hx, float px,
                         float c, float R, float eps, Vec3 base, Vec3 gx,
                         const float* __restrict occ) {
#ifdef SCATTERLAB_GATHER_AVX2
  if (kAvx2)
    return gather_detail::rowAvx2(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, occ,
                                  0.0f, 0.0f, false);
#endif
  row<true, false>(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, occ, 0.0f, 0.0f);
}

void gradientRowBounded(float* __restrict r0, float* __restrict g0, float* __restrict b0,
                        float* __restrict w0, int i0, int i1, float lox, float hx, float px,
                        float c, float R, float eps, Vec3 base, Vec3 gx,
                        const float* __restrict occ, float lo, float hi) {
#ifdef SCATTERLAB_GATHER_AVX2
  if (kAvx2)
    return gather_detail::rowAvx2(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, occ, lo,
                                  hi, true);
#endif
  if (occ)
    row<true, true>(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, occ, lo, hi);
  else
    row<false, true>(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, nullptr, lo, hi);
}

void normaliseSpan(const float* __restrict r, const float* __restrict g, const float* __restrict b,
                   const float* __restrict w, int i0, int i1, float* __restrict qr,
                   float* __restrict qg, float* __restrict qb) {
#ifdef SCATTERLAB_GATHER_AVX2
  if (kAvx2) return gather_detail::normaliseAvx2(r, g, b, w, i0, i1, qr, qg, qb);
#endif
  gather_detail::normalise(r, g, b, w, i0, i1, qr, qg, qb);
}

}  // namespace scatterlab
