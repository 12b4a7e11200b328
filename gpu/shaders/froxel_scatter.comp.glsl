// froxel, pass 1 (cpu/froxel.cpp, froxelAccumulate): one invocation per froxel column, front
// to back over the depth slices; at each froxel's centre the in-scattering of its slice is
// composited, and (L, T) after the froxel is stored. On a driver that caps loop iterations the
// lights may be split over dispatches (gpu::lightDispatches): this one takes lights uLightFirst,
// uLightFirst + uLightStride, … and, unless it is the first (uLightFirst 0), adds the L the ones
// before it stored at each froxel.
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = BINDING_FROXEL_IMAGE) uniform image3D uFroxels;
#ifdef SL_TRANSMITTANCE_MAP
layout(r32f, binding = BINDING_TRANSMITTANCE_MAP_IMAGE) uniform readonly image3D uMap;
uniform int uMapRes;
#endif
uniform ivec3 uGrid;
uniform int uLightFirst;
uniform int uLightStride;
// The view depths of the slices' boundaries 0 … uGrid.z: FroxelSlicing::depth (shading/
// screen_march.h) computed by the host, the CPU's floats. A GPU's pow is further off than its
// other built-ins, and a boundary that moves moves the froxel's centre: next to a lamp, where
// the source radiance grows as 1/distance², a few ulps of pow moved pixels by 6e-4 relative
// (the population's fog_shaft_3 with the built-ins simulated 4 ulps off, 2026-12-08).
layout(std430, binding = BINDING_FROXEL_DEPTHS) readonly buffer FroxelDepths {
  float sliceDepths[];
};

#ifdef SL_TRANSMITTANCE_MAP
// Grid3::sample of light li's map at x (inside the box).
float mapAt(int li, vec3 x) {
  vec3 u = (x - uBoxMin) / ((uBoxMax - uBoxMin) / float(uMapRes)) - 0.5;
  u = clamp(u, vec3(0.0), vec3(float(uMapRes - 1)));
  ivec3 i0 = min(ivec3(u), ivec3(uMapRes - 2));
  vec3 f = u - vec3(i0);
  ivec3 o = ivec3(0, 0, li * uMapRes);
  float c[8];
  for (int c8 = 0; c8 < 8; ++c8)
    c[c8] = imageLoad(uMap, o + i0 + ivec3(c8 & 1, (c8 >> 1) & 1, (c8 >> 2) & 1)).r;
  float c00 = c[0] + (c[1] - c[0]) * f.x;
  float c10 = c[2] + (c[3] - c[2]) * f.x;
  float c01 = c[4] + (c[5] - c[4]) * f.x;
  float c11 = c[6] + (c[7] - c[6]) * f.x;
  float c0 = c00 + (c10 - c00) * f.y;
  float c1 = c01 + (c11 - c01) * f.y;
  return c0 + (c1 - c0) * f.z;
}

// TransmittanceMaps::source: Σ_l E_l(x)·f(ω_l → ω)·map_l(x).
vec3 mapSource(vec3 x, vec3 toViewer) {
  vec3 s = vec3(0.0);
  for (int li = uLightFirst; li < uLightCount; li += max(uLightStride, 1)) {
    GpuLight l = lights[li];
    vec3 toLight;
    float dist, dist2, f;
    if (!lightGeometry(l, x, true, toLight, dist, dist2, f) || f <= 0.0) continue;
    vec3 irradiance = int(l.positionType.w) == 2 ? l.intensityCosOuter.rgb
                                                 : l.intensityCosOuter.rgb * (f / dist2);
    s += irradiance * (phaseEvalCos(dot(-toLight, toViewer)) * mapAt(li, x));
  }
  return s;
}
#endif

void main() {
  ivec2 ij = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(ij, uGrid.xy))) return;
  // columnRay and the slices' clip in the CPU's arithmetic (cpuDiv, cpuDot, `precise`).
  precise vec2 fs = (vec2(ij) + 0.5) * uSize;
  vec3 dir = cameraRay(vec2(cpuDiv(fs.x, float(uGrid.x)), cpuDiv(fs.y, float(uGrid.y))));
  float c = cpuDot(dir, uForward);
  // Each slice clipped to the column's piece inside the box (cpu/froxel.cpp).
  float t0 = 0.0, t1 = -1.0;
  if (uSigmaT > 0.0 && !intersectBox(uEye, dir, 0.0, kInf, t0, t1)) t1 = -1.0;
  vec3 L = vec3(0.0);
  float T = 1.0;
  for (int k = 0; k < uGrid.z; ++k) {
    float za = sliceDepths[k], zb = sliceDepths[k + 1];
    float ta = max(cpuDiv(za, c), t0), tb = min(cpuDiv(zb, c), t1);
    precise vec3 x = uEye + dir * (0.5 * (ta + tb));
    float D = tb > ta ? densityAtIndex(x * uDensityScale + uDensityOffset) : 0.0;
    if (D > 0.0) {
      float a = stepTransmittance(uSigmaT * D * (tb - ta));
#ifdef SL_TRANSMITTANCE_MAP
      vec3 S = mapSource(x, -dir);
#else
      vec3 S = sourceRadiancePart(x, -dir, uLightFirst, max(uLightStride, 1));
#endif
      L += (T * uAlbedo * (1.0 - a)) * S;
      T *= a;
    }
    vec3 before = uLightFirst > 0 ? imageLoad(uFroxels, ivec3(ij, k)).rgb : vec3(0.0);
    imageStore(uFroxels, ivec3(ij, k), vec4(L + before, T));
  }
}
