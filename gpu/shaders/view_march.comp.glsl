// The compute view march (render.gpu_pipeline = compute; gpu/view_march.h): one invocation per
// pixel, front to back with early exit, the CPU marcher's steps exactly (cpu/ray_marcher.h
// marchWith): n = stepCount(t1 − t0, step) equal steps between the box entry and the box exit (or
// the first surface), lookups at the steps' middles in index space u0 + i·du,
//   L += T·Ω·(1 − a)·S,  T *= a,  a = exp(−σt·D·Δt),
// until T <= uMinT; then L + T·L_p (the surface's, from the surface pass) or L + T·background.
// camera.spp = k²: k × k stratum centres per pixel, box filter (as the CPU). With SL_SKIP the
// steps inside blocks of zero density (block_walk.glsl) are jumped over: they add exactly 0, so
// the image is the plain march's bit for bit. Every march counts the steps it looked up and the
// steps it jumped over into uMarchCounts (64-bit sums as two 32-bit words each). After
// common.glsl, screen_common.glsl (and block_walk.glsl with SL_SKIP). With SL_FACTOR_LIGHTS, on
// a driver that caps loop iterations, the lights may be split over dispatches
// (gpu::lightDispatches): this one multiplies V by the part of A of lights uLightFirst,
// uLightFirst + uLightStride, … and, unless it is the first (uLightFirst 0, which also adds the
// background or the surface and counts the steps), adds its L to the image's.
layout(local_size_x = 8, local_size_y = 8) in;

#ifdef SL_FACTOR_LIGHTS
layout(rgba32f, binding = BINDING_OUTPUT_IMAGE) uniform image2D uOutput;
uniform int uLightFirst;
uniform int uLightStride;
#else
layout(rgba32f, binding = BINDING_OUTPUT_IMAGE) uniform writeonly image2D uOutput;
const int uLightFirst = 0;
#endif
layout(binding = BINDING_RADIANCE_TEXTURE) uniform sampler3D uRadiance;
uniform vec3 uRadScale;  // world -> radiance index
uniform vec3 uRadOffset;
uniform ivec3 uRadDims;
uniform float uStep;
uniform float uMinT;
uniform int uStrata;  // k: k × k rays per pixel
uniform vec3 uBackground;
// Mirrored by gpu::GpuMarchCounters (gpu/records.h): steps looked up, steps jumped over, each
// as (low word, high word).
layout(std430, binding = BINDING_COUNTERS) buffer MarchCounts { uint marchCounts[4]; };
uint stepsLooked = 0u, stepsSkipped = 0u;  // this invocation's
shared uint groupLooked, groupSkipped;

// Grid3::sampleIndex of the RGBA radiance volume at index u: the eight neighbours interpolated
// in float, in the CPU's order (densityAtIndex's twin, per channel). Its rgb is S; with SL_FUSED
// (gpu::Volume::densityInAlpha, the density's grid) its alpha is D: both in one lookup.
vec4 radianceAtIndex(vec3 u) {
  u = clamp(u, vec3(0.0), vec3(uRadDims - 1));
  ivec3 i0 = min(ivec3(u), uRadDims - 1);
  ivec3 i1 = min(i0 + 1, uRadDims - 1);
  vec3 f = u - vec3(i0);
  vec4 c000 = texelFetch(uRadiance, i0, 0);
  vec4 c100 = texelFetch(uRadiance, ivec3(i1.x, i0.y, i0.z), 0);
  vec4 c010 = texelFetch(uRadiance, ivec3(i0.x, i1.y, i0.z), 0);
  vec4 c110 = texelFetch(uRadiance, ivec3(i1.x, i1.y, i0.z), 0);
  vec4 c001 = texelFetch(uRadiance, ivec3(i0.x, i0.y, i1.z), 0);
  vec4 c101 = texelFetch(uRadiance, ivec3(i1.x, i0.y, i1.z), 0);
  vec4 c011 = texelFetch(uRadiance, ivec3(i0.x, i1.y, i1.z), 0);
  vec4 c111 = texelFetch(uRadiance, i1, 0);
  vec4 c00 = c000 + (c100 - c000) * f.x;
  vec4 c10 = c010 + (c110 - c010) * f.x;
  vec4 c01 = c001 + (c101 - c001) * f.x;
  vec4 c11 = c011 + (c111 - c011) * f.x;
  vec4 c0 = c00 + (c10 - c00) * f.y;
  vec4 c1 = c01 + (c11 - c01) * f.y;
  return c0 + (c1 - c0) * f.z;
}

// One ray: radiance in rgb, the pixel's alpha in a (1 − T, or 1 where a surface is hit).
vec4 marchRay(vec3 dir, ivec2 pixel) {
  vec3 L = vec3(0.0);
  float T = 1.0;
  float tSurface = surfaceDistance(pixel);
  bool hit = tSurface < kInf;
  float t0, t1;
  if (uSigmaT > 0.0 && intersectBox(uEye, dir, 0.0, kInf, t0, t1) && t1 > t0) {
    if (hit) t1 = min(t1, tSurface);
    if (t1 > t0) {
      // The CPU's steps bit for bit (cpuDiv, `precise`; the ray from cameraRay).
      int n = stepCount(t1 - t0, uStep);
      float dt = cpuDiv(t1 - t0, float(n));
      precise vec3 u0 = (uEye + dir * (t0 + 0.5 * dt)) * uDensityScale + uDensityOffset;
      precise vec3 du = dir * dt * uDensityScale;
#ifdef SL_SKIP
      BlockWalk walk = blockWalk(u0, du, n);
#endif
      int i = 0;
      while (i < n && T > uMinT) {
        int end = n;
#ifdef SL_SKIP
        bool empty;
        end = blockSpan(walk, i, empty);
        if (empty) {
          stepsSkipped += uint(end - i);
          i = end;
          continue;
        }
#endif
        for (; i < end && T > uMinT; ++i) {
          ++stepsLooked;
          precise vec3 u = u0 + float(i) * du;  // the CPU's lookup points, as it rounds them
          precise float t = t0 + (float(i) + 0.5) * dt;
#ifdef SL_FUSED
          vec4 DS = radianceAtIndex(u);
          float D = DS.a;
          if (!(D > 0.0)) continue;
          vec3 S = DS.rgb;
#else
          float D = densityAtIndex(u);
          if (!(D > 0.0)) continue;
          precise vec3 x = uEye + dir * t;
          vec3 S = radianceAtIndex(x * uRadScale + uRadOffset).rgb;
#endif
#ifdef SL_FACTOR_LIGHTS
          // The volume holds V = S / A; where V = 0 (outside every spot cone, or fully
          // shadowed) S is 0 without evaluating A, as on the CPU.
          if (S != vec3(0.0))
            S *= lightFactorStepPart(uEye, dir, t, dt, uLightFirst, max(uLightStride, 1));
#endif
          float a = stepTransmittance(uSigmaT * D * dt);
          L += (T * uAlbedo * (1.0 - a)) * S;
          T *= a;
        }
      }
    }
  }
  // A later part of the lights: its L only (the first part added what lies behind the medium).
  if (uLightFirst > 0) return vec4(L, hit ? 1.0 : 1.0 - T);
  if (!hit) return vec4(L + T * uBackground, 1.0 - T);
#ifdef SL_OBJECTS
  // Below uMinT the surface's share is below it too (as for the medium).
  vec3 Lp = texelFetch(uSurfaceRadiance, pixel, 0).rgb;
  return vec4(T > uMinT ? L + T * Lp : L, 1.0);
#else
  return vec4(L, 1.0);
#endif
}

// Adds v to the 64-bit counter at word w (low) and w + 1 (high).
void addCount(uint w, uint v) {
  uint before = atomicAdd(marchCounts[w], v);
  if (before + v < before) atomicAdd(marchCounts[w + 1u], 1u);
}

void main() {
  if (gl_LocalInvocationIndex == 0u) {
    groupLooked = 0u;
    groupSkipped = 0u;
  }
  memoryBarrierShared();
  barrier();
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x < int(uSize.x) && p.y < int(uSize.y)) {
    vec4 sum = vec4(0.0);
    for (int j = 0; j < uStrata; ++j)
      for (int i = 0; i < uStrata; ++i) {
        precise vec2 f = vec2(p) + vec2(cpuDiv(float(i) + 0.5, float(uStrata)),
                                        cpuDiv(float(j) + 0.5, float(uStrata)));
        sum += marchRay(cameraRay(f), p);
      }
    sum /= float(uStrata * uStrata);
#ifdef SL_FACTOR_LIGHTS
    if (uLightFirst > 0) sum.rgb += imageLoad(uOutput, p).rgb;
#endif
    imageStore(uOutput, p, sum);
  }
  // The steps are the first part's (every part walks the same ones): a later part counts none.
  if (uLightFirst > 0) {
    stepsLooked = 0u;
    stepsSkipped = 0u;
  }
  // One global atomic per workgroup and counter.
  atomicAdd(groupLooked, stepsLooked);
  atomicAdd(groupSkipped, stepsSkipped);
  memoryBarrierShared();
  barrier();
  if (gl_LocalInvocationIndex == 0u && uLightFirst == 0) {
    addCount(0u, groupLooked);
    addCount(2u, groupSkipped);
  }
}
