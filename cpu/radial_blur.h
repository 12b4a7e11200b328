#pragma once
/// `radial-blur` on the CPU (Mitchell, GPU Gems 3 ch. 13; docs/radial-blur.md). Per light l:
///  1. occlusion pre-pass P_l at (W/ds) × (H/ds) pixels: black where the view ray hits an
///     object nearer than the light (occluders), else the light's unshadowed in-scattering
///     along the view ray, Σ_steps T·Ω·(1 − e^(−σt·D·Δt))·E_l(x)·f(ω_l → ω) — Mitchell's
///     analytic daylight term L(s, θ) with the real density: the medium's optical depth along
///     the view ray dims it, no light transmittance and no shadow enters it;
///  2. the radial blur (his Eq. 4): R_l(φ) = exposure · Σ_{i<n} decay^i · weight · P_l(φ_i) / n,
///     φ_i = φ − i·Δφ, Δφ = (φ − α_l)·density/n, α_l the light's screen position clamped to the
///     guard band (shading/post_process.h), P_l read bilinearly with its edge texels repeated.
/// The image is T·L0 (background, or the surface's L_p of SurfaceRadiance) + Σ_l R_l, alpha
/// 1 − T (1 on a surface). A light behind the camera is a ConfigError (nothing to blur towards).

#include "core/image.h"
#include "core/scene.h"
#include "core/stages.h"
#include "shading/post_process.h"

namespace scatterlab {

/// Light `light`'s pre-pass (step 1) at (W/ds) × (H/ds), ray of pixel (i, j) through image
/// point ((i + 1/2)·ds, (j + 1/2)·ds).
Image radialBlurPrePass(const Scene& scene, const DensityGrid& density, int light, int ds,
                        const MarchSettings& march);

/// R(φ) of step 2 for every pixel of the W × H image from a pre-pass `pre` of `downsample`
/// times fewer pixels per side, towards the screen point (ax, ay).
Image radialBlur(const Image& pre, int downsample, int width, int height, float ax, float ay,
                 const RadialBlurSettings& s);

/// The whole method: base image plus every light's blurred pre-pass.
Image renderRadialBlur(const Scene& scene, const DensityGrid& density, const RadialBlurSettings& s,
                       const MarchSettings& march, float delta1);

/// Registers the CPU variant of integrator "radial-blur".
void registerRadialBlur();

}  // namespace scatterlab
