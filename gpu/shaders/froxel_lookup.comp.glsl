// froxel, pass 2 (cpu/froxel.cpp, froxelLookup and froxelRender): one trilinear lookup per
// pixel at the far depth, then T·background; where the pixel's ray hits a surface (the surface
// pass), the lookup is at the surface's view depth, then T·L_p (above min_transmittance).
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = BINDING_FROXEL_IMAGE) uniform readonly image3D uFroxels;
layout(rgba32f, binding = BINDING_OUTPUT_IMAGE) uniform writeonly image2D uOut;
uniform ivec3 uGrid;
uniform float uNear;
uniform float uFar;
uniform int uExponential;
uniform vec3 uBackground;
uniform float uMinTransmittance;

// FroxelSlicing::coordinate (shading/screen_march.h).
float sliceCoordinate(float z) {
  if (!(z > uNear)) return 0.0;
  float s = uExponential != 0 ? log(z / uNear) / log(uFar / uNear) : (z - uNear) / (uFar - uNear);
  return min(float(uGrid.z), s * float(uGrid.z));
}

// Boundary b: (L, T) after slice b − 1; boundary 0 is (0, 1).
vec4 boundary(int i, int j, int b) {
  return b == 0 ? vec4(0.0, 0.0, 0.0, 1.0) : imageLoad(uFroxels, ivec3(i, j, b - 1));
}

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, ivec2(uSize)))) return;
  float hitT = surfaceDistance(p);
  float w = sliceCoordinate(isinf(hitT) ? uFar : hitT * dot(cameraRay(vec2(p) + 0.5), uForward));
  vec2 g = clamp((vec2(p) + 0.5) / uSize * vec2(uGrid.xy) - 0.5, vec2(0.0), vec2(uGrid.xy - 1));
  int i0 = min(int(g.x), uGrid.x - 1), j0 = min(int(g.y), uGrid.y - 1);
  int i1 = min(i0 + 1, uGrid.x - 1), j1 = min(j0 + 1, uGrid.y - 1);
  int b0 = min(int(w), uGrid.z - 1);
  float fx = g.x - float(i0), fy = g.y - float(j0), fz = w - float(b0);
  vec4 acc = vec4(0.0);
  for (int c = 0; c < 8; ++c) {
    int i = (c & 1) != 0 ? i1 : i0, j = (c & 2) != 0 ? j1 : j0, b = (c & 4) != 0 ? b0 + 1 : b0;
    float weight = ((c & 1) != 0 ? fx : 1.0 - fx) * ((c & 2) != 0 ? fy : 1.0 - fy) *
                   ((c & 4) != 0 ? fz : 1.0 - fz);
    if (weight != 0.0) acc += weight * boundary(i, j, b);
  }
#ifdef SL_OBJECTS
  if (!isinf(hitT)) {
    vec3 lp = texelFetch(uSurfaceRadiance, p, 0).rgb;
    imageStore(uOut, p, vec4(acc.a > uMinTransmittance ? acc.rgb + acc.a * lp : acc.rgb, 0.0));
    return;
  }
#endif
  imageStore(uOut, p, vec4(acc.rgb + acc.a * uBackground, acc.a));
}
