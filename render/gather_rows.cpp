#include "render/gather_rows.h"

namespace scatterlab {

void gradientRow(float* __restrict r0, float* __restrict g0, float* __restrict b0,
                 float* __restrict w0, int i0, int i1, float lox, float hx, float px, float c,
                 float R, float eps, Vec3 base, Vec3 gx) {
  const float R2 = R * R, e2 = eps * eps * R2;
  const float br = base.x, bg = base.y, bb = base.z, gr = gx.x, gg = gx.y, gb = gx.z;
  for (int i = i0; i <= i1; ++i) {
    const float dx = (lox + (float(i) + 0.5f) * hx) - px;
    const float d2 = dx * dx + c;
    const float wAll = R / std::sqrt(std::max(d2, e2));
    const float w = d2 < R2 ? wAll : 0.0f;
    r0[i] += w * (br + dx * gr);
    g0[i] += w * (bg + dx * gg);
    b0[i] += w * (bb + dx * gb);
    w0[i] += w;
  }
}

void gradientRowWeighted(float* __restrict r0, float* __restrict g0, float* __restrict b0,
                         float* __restrict w0, int i0, int i1, float lox, float hx, float px,
                         float c, float R, float eps, Vec3 base, Vec3 gx,
                         const float* __restrict occ) {
  const float R2 = R * R, e2 = eps * eps * R2;
  const float br = base.x, bg = base.y, bb = base.z, gr = gx.x, gg = gx.y, gb = gx.z;
  for (int i = i0; i <= i1; ++i) {
    const float dx = (lox + (float(i) + 0.5f) * hx) - px;
    const float d2 = dx * dx + c;
    const float wAll = occ[i] * R / std::sqrt(std::max(d2, e2));
    const float w = d2 < R2 ? wAll : 0.0f;
    r0[i] += w * (br + dx * gr);
    g0[i] += w * (bg + dx * gg);
    b0[i] += w * (bb + dx * gb);
    w0[i] += w;
  }
}

namespace {

/// gradientRowBounded's body; the occlusion factor is a template parameter so that the loop
/// without it stays a plain vectorisable one (no per-voxel pointer test).
template <bool kOcc>
inline void boundedRow(float* __restrict r0, float* __restrict g0, float* __restrict b0,
                       float* __restrict w0, int i0, int i1, float lox, float hx, float px, float c,
                       float R, float eps, Vec3 base, Vec3 gx, const float* __restrict occ,
                       float lo, float hi) {
  const float R2 = R * R, e2 = eps * eps * R2;
  const float br = base.x, bg = base.y, bb = base.z, gr = gx.x, gg = gx.y, gb = gx.z;
  for (int i = i0; i <= i1; ++i) {
    const float dx = (lox + (float(i) + 0.5f) * hx) - px;
    const float d2 = dx * dx + c;
    float wAll = R / std::sqrt(std::max(d2, e2));
    if constexpr (kOcc) wAll *= occ[i];
    const float w = d2 < R2 ? wAll : 0.0f;
    r0[i] += w * std::min(std::max(br + dx * gr, lo), hi);
    g0[i] += w * std::min(std::max(bg + dx * gg, lo), hi);
    b0[i] += w * std::min(std::max(bb + dx * gb, lo), hi);
    w0[i] += w;
  }
}

}  // namespace

void gradientRowBounded(float* __restrict r0, float* __restrict g0, float* __restrict b0,
                        float* __restrict w0, int i0, int i1, float lox, float hx, float px,
                        float c, float R, float eps, Vec3 base, Vec3 gx,
                        const float* __restrict occ, float lo, float hi) {
  if (occ)
    boundedRow<true>(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, occ, lo, hi);
  else
    boundedRow<false>(r0, g0, b0, w0, i0, i1, lox, hx, px, c, R, eps, base, gx, occ, lo, hi);
}

}  // namespace scatterlab
