// light-space-march (Tóth & Umenhoffer 2009), the GPU twin of cpu/light_space_march.cpp
// (LightSpaceMarcher::march, blockSum): line for line the same sums.
//   SL_MARCH:     one invocation per pixel: the pixel's interleaving class k = (x mod M) +
//                 M·(y mod M); the terms n ≡ k (mod M²) of its N-step view ray go to the "out"
//                 image (rgb), its boundary term T_N·background and alpha 1 − T_N to "base".
//                 SL_OBJECTS: the ray ends at the surface of the surface pass, whose boundary
//                 term is T_N·L_p (alpha 1), and v_l comes from the shadow maps (shadow.glsl).
//   SL_BLOCK_SUM: one direction of the separable M-wide sliding-window sum (blockWindowStart of
//                 shading/post_process.h) from "in" to "out"; the vertical pass adds "base" and writes
//                 base's alpha.
#ifndef SL_BLOCK_SUM
#ifndef SL_MARCH
#define SL_MARCH  // the default variant
#endif
#endif
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = BINDING_SCREEN_OUT_IMAGE) uniform writeonly image2D uOut;
layout(rgba32f, binding = BINDING_SCREEN_BASE_IMAGE) uniform image2D uBase;
uniform ivec2 uImageSize;
uniform int uInterleave;  // M

#ifdef SL_MARCH
uniform vec3 uForward;
uniform vec3 uRight;
uniform vec3 uUp;
uniform vec2 uTanHalf;  // (tan(fov/2)·aspect, tan(fov/2))
uniform int uSteps;     // N
uniform float uAlbedo;
uniform float uMeanDensity;  // D̄ (light_transmittance "mean")
uniform vec3 uBackground;

#ifdef SL_OBJECTS
// The surface pass (gpu/stages.h ScreenSurfaces): the first surface's view-ray distance (3e38
// where none) and its L_p. v_l(x) is shadow.glsl's lightVisibility (render.shadow_map).
layout(binding = BINDING_SURFACE_TEXTURE) uniform sampler2D uSurfaceDistance;
layout(binding = BINDING_SURFACE_RADIANCE_TEXTURE) uniform sampler2D uSurfaceRadiance;
#endif

// LightSpaceMarcher::source: Σ_l E_l·f·v_l·T_l at x towards the viewer.
vec3 lsmSource(vec3 x, vec3 toViewer) {
  vec3 s = vec3(0.0);
  for (int li = 0; li < uLightCount; ++li) {
    GpuLight l = lights[li];
    vec3 toLight;
    float dist, dist2, cone;
    if (!lightGeometry(l, x, true, toLight, dist, dist2, cone) || cone <= 0.0) continue;
    bool directional = int(l.positionType.w) == 2;
    vec3 irradiance = directional ? l.intensityCosOuter.rgb : l.intensityCosOuter.rgb * (cone / dist2);
#ifdef SL_OBJECTS
    float vis = lightVisibility(li, x);
    if (vis <= 0.0) continue;
#else
    const float vis = 1.0;  // v_l = 1 without objects
#endif
#ifdef SL_TRACED
    float tau = opticalDepth(x, lightSegmentEnd(l, x, toLight, dist), uDelta1);
#else
    // lengthInBox (shading/post_process.h)
    float t0, t1, tau = 0.0;
    if (intersectBox(x, toLight, 0.0, directional ? kInf : dist, t0, t1) && t1 > t0)
      tau = uMeanDensity * (t1 - t0);
#endif
    s += irradiance * (vis * phaseEvalCos(dot(-toLight, toViewer)) * exp(-uSigmaT * tau));
  }
  return s;
}

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= uImageSize.x || px.y >= uImageSize.y) return;
  // The camera's ray as the CPU rounds it (cpu_arithmetic.glsl): its box entry and exit, and
  // where it passes a lamp, are the CPU's.
  vec3 dir = cpuCameraRay(vec2(px) + 0.5, vec2(uImageSize), uForward, uRight, uUp, uTanHalf);
  int stride = uInterleave * uInterleave;
  int first = (px.x % uInterleave) + uInterleave * (px.y % uInterleave);
  vec3 L = vec3(0.0);
  float T = 1.0;
  float t0, t1;
#ifdef SL_OBJECTS
  float hitT = texelFetch(uSurfaceDistance, px, 0).r;
  bool hasHit = hitT < 1.0e38;
#else
  const float hitT = kInf;
  const bool hasHit = false;
#endif
  if (uSigmaT > 0.0 && intersectBox(uEye, dir, 0.0, kInf, t0, t1) && t1 > t0 &&
      min(t1, hitT) > t0) {
    // From the box entry to the surface or the box exit (LightSpaceMarcher::march).
    t1 = min(t1, hitT);
    int n = uSteps;
    float dt = cpuDiv(t1 - t0, float(n));
    precise vec3 u0 = (uEye + dir * (t0 + 0.5 * dt)) * uDensityScale + uDensityOffset;
    precise vec3 du = dir * dt * uDensityScale;
    for (int i = 0; i < n; ++i) {
      precise vec3 ui = u0 + float(i) * du;
      float D = densityAtIndex(ui);
      if (D <= 0.0) continue;
      float a = stepTransmittance(uSigmaT * D * dt);
      if (i % stride == first) {
        precise vec3 p = uEye + dir * (t0 + (float(i) + 0.5) * dt);
        L += (T * uAlbedo * (1.0 - a)) * lsmSource(p, -dir);
      }
      T *= a;
    }
  }
  imageStore(uOut, px, vec4(L, 0.0));
#ifdef SL_OBJECTS
  if (hasHit) {
    imageStore(uBase, px, vec4(T * texelFetch(uSurfaceRadiance, px, 0).rgb, 1.0));
    return;
  }
#endif
  imageStore(uBase, px, vec4(T * uBackground, 1.0 - T));
}
#endif

#ifdef SL_BLOCK_SUM
layout(rgba32f, binding = BINDING_SCREEN_IN_IMAGE) uniform readonly image2D uIn;
uniform int uVertical;  // 0: sum along x, 1: along y and add base

int blockWindowStart(int x, int m, int size) {
  return clamp(x - (m - 1) / 2, 0, size - m);
}

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= uImageSize.x || px.y >= uImageSize.y) return;
  vec3 sum = vec3(0.0);
  if (uVertical == 0) {
    int s = blockWindowStart(px.x, uInterleave, uImageSize.x);
    for (int k = 0; k < uInterleave; ++k) sum += imageLoad(uIn, ivec2(s + k, px.y)).rgb;
    imageStore(uOut, px, vec4(sum, 0.0));
  } else {
    int s = blockWindowStart(px.y, uInterleave, uImageSize.y);
    for (int k = 0; k < uInterleave; ++k) sum += imageLoad(uIn, ivec2(px.x, s + k)).rgb;
    vec4 base = imageLoad(uBase, px);
    imageStore(uOut, px, vec4(base.rgb + sum, base.a));
  }
}
#endif
