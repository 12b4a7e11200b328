// radial-blur (Mitchell, GPU Gems 3 ch. 13), the GPU twin of cpu/radial_blur.cpp:
//   SL_BASE:    per pixel, T·background of the view ray (march_step steps, stopping below
//               min_transmittance) into "out" (rgb) with alpha 1 − T (marchImage with S = 0);
//   SL_PREPASS: per pre-pass pixel, light uLight's unshadowed in-scattering along the view ray
//               through image point ((i + 1/2)·ds, (j + 1/2)·ds) (radialBlurPrePass) into "out";
//   SL_OBJECTS: the view rays end at the surface pass's first surface; the base pass adds T·L_p
//               there, and the pre-pass leaves pixels whose surface hides the light black.
//   SL_BLUR:    per pixel, "out" += exposure·Σ_{i<n} decay^i·weight·P(φ_i)/n (radialBlur), P
//               the pre-pass ("in") read bilinearly with its edge texels repeated.
#if !defined(SL_PREPASS) && !defined(SL_BLUR)
#ifndef SL_BASE
#define SL_BASE  // the default variant
#endif
#endif
layout(local_size_x = 8, local_size_y = 8) in;
uniform ivec2 uImageSize;  // the full image

#if defined(SL_BASE) || defined(SL_PREPASS)
layout(rgba32f, binding = BINDING_SCREEN_OUT_IMAGE) uniform writeonly image2D uOut;
uniform vec3 uForward;
uniform vec3 uRight;
uniform vec3 uUp;
uniform vec2 uTanHalf;
uniform float uStep;  // march_step
uniform float uMinTransmittance;
uniform float uAlbedo;
uniform vec3 uBackground;
uniform int uLight;       // SL_PREPASS: the light
uniform int uDownsample;  // SL_PREPASS: ds
uniform ivec2 uPassSize;  // the size of the image this pass writes
#ifdef SL_OBJECTS
// The surface pass (gpu/stages.h ScreenSurfaces): the first surface's view-ray distance (3e38
// where none) and its L_p, at full resolution.
layout(binding = BINDING_SURFACE_TEXTURE) uniform sampler2D uSurfaceDistance;
layout(binding = BINDING_SURFACE_RADIANCE_TEXTURE) uniform sampler2D uSurfaceRadiance;
#endif

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= uPassSize.x || px.y >= uPassSize.y) return;
#ifdef SL_PREPASS
  vec2 f = (vec2(px) + 0.5) * float(uDownsample);
#else
  vec2 f = vec2(px) + 0.5;
#endif
  // The camera's ray as the CPU rounds it (cpu_arithmetic.glsl).
  vec3 dir = cpuCameraRay(f, vec2(uImageSize), uForward, uRight, uUp, uTanHalf);
  vec3 L = vec3(0.0);
  float T = 1.0;
  float t0, t1;
#ifdef SL_OBJECTS
  // The full-resolution pixel of the ray's image point (the pre-pass's own pixel when ds = 1).
  ivec2 q = min(ivec2(f), uImageSize - 1);
  float hitT = texelFetch(uSurfaceDistance, q, 0).r;
  bool hasHit = hitT < 1.0e38;
#else
  const float hitT = kInf;
  const bool hasHit = false;
#endif
  bool inBox = uSigmaT > 0.0 && intersectBox(uEye, dir, 0.0, kInf, t0, t1) && t1 > t0;
#ifdef SL_PREPASS
  // An occluder (a surface nearer than the light; any surface for a directional light) is
  // black in the pre-pass (radialBlurPrePass).
  GpuLight occl = lights[uLight];
  if (hasHit && (int(occl.positionType.w) == 2 || hitT < length(occl.positionType.xyz - uEye)))
    inBox = false;
#endif
  if (inBox && min(t1, hitT) > t0) {
    t1 = min(t1, hitT);
    int n = stepCount(t1 - t0, uStep);
    float dt = cpuDiv(t1 - t0, float(n));
    precise vec3 u0 = (uEye + dir * (t0 + 0.5 * dt)) * uDensityScale + uDensityOffset;
    precise vec3 du = dir * dt * uDensityScale;
    for (int i = 0; i < n && T > uMinTransmittance; ++i) {
      precise vec3 ui = u0 + float(i) * du;
      float D = densityAtIndex(ui);
      if (D <= 0.0) continue;
      float a = stepTransmittance(uSigmaT * D * dt);
#ifdef SL_PREPASS
      precise vec3 p = uEye + dir * (t0 + (float(i) + 0.5) * dt);
      vec3 toLight;
      float dist, dist2, cone;
      GpuLight l = lights[uLight];
      if (lightGeometry(l, p, false, toLight, dist, dist2, cone) && cone > 0.0) {
        vec3 e = int(l.positionType.w) == 2 ? l.intensityCosOuter.rgb
                                            : l.intensityCosOuter.rgb * (cone / dist2);
        L += (T * uAlbedo * (1.0 - a) * phaseEvalCos(dot(-toLight, -dir))) * e;
      }
#endif
      T *= a;
    }
  }
#ifdef SL_PREPASS
  imageStore(uOut, px, vec4(L, 0.0));
#else
#ifdef SL_OBJECTS
  if (hasHit) {
    // marchImage: T·L_p above min_transmittance, alpha 1 (the surface is opaque).
    vec3 lp = texelFetch(uSurfaceRadiance, px, 0).rgb;
    imageStore(uOut, px, vec4(T > uMinTransmittance ? T * lp : vec3(0.0), 1.0));
    return;
  }
#endif
  imageStore(uOut, px, vec4(T * uBackground, 1.0 - T));
#endif
}
#endif

#ifdef SL_BLUR
layout(rgba32f, binding = BINDING_SCREEN_IN_IMAGE) uniform readonly image2D uIn;
layout(rgba32f, binding = BINDING_SCREEN_BASE_IMAGE) uniform image2D uBase;  // accumulated
uniform ivec2 uPreSize;
uniform int uDownsample;
uniform vec2 uLightPos;  // α, continuous pixel coordinates
uniform int uSamples;
uniform float uBlurDensity;  // Mitchell's density
uniform float uDecay;
uniform float uScale;  // exposure·weight/n

vec3 fetch(int i, int j) {
  return imageLoad(uIn, ivec2(i, j)).rgb;
}

// bilinear (cpu/radial_blur.cpp)
vec3 bilinear(float u, float v) {
  u = clamp(u, 0.0, float(uPreSize.x - 1));
  v = clamp(v, 0.0, float(uPreSize.y - 1));
  int i0 = min(int(u), uPreSize.x - 1), j0 = min(int(v), uPreSize.y - 1);
  int i1 = min(i0 + 1, uPreSize.x - 1), j1 = min(j0 + 1, uPreSize.y - 1);
  float fu = u - float(i0), fv = v - float(j0);
  vec3 a = fetch(i0, j0) + (fetch(i1, j0) - fetch(i0, j0)) * fu;
  vec3 b = fetch(i0, j1) + (fetch(i1, j1) - fetch(i0, j1)) * fu;
  return a + (b - a) * fv;
}

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= uImageSize.x || px.y >= uImageSize.y) return;
  vec2 f = vec2(px) + 0.5;
  vec2 d = (f - uLightPos) * uBlurDensity / float(uSamples);
  float ds = float(uDownsample);
  vec3 sum = vec3(0.0);
  float decay = 1.0;
  for (int i = 0; i < uSamples; ++i) {
    vec2 p = f - float(i) * d;
    sum += decay * bilinear(p.x / ds - 0.5, p.y / ds - 0.5);
    decay *= uDecay;
  }
  vec4 base = imageLoad(uBase, px);
  imageStore(uBase, px, vec4(base.rgb + sum * uScale, base.a));
}
#endif
