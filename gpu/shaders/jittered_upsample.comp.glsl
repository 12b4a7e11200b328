// jittered-march, pass 2 (cpu/jittered_march.cpp, upsampleWeights and jitteredMarch): each
// full-resolution pixel takes the bilateral average of its four low-resolution neighbours
// (bilinear × e^(−|Δdepth| / (σ·depth))), then adds T·background, or T·L_p of the surface
// pass's first surface (above min_transmittance; alpha 1) where the pixel's ray hits one.
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = BINDING_LOW_RES_IMAGE) uniform readonly image2D uLow;
layout(r32f, binding = BINDING_LOW_RES_DEPTH_IMAGE) uniform readonly image2D uLowDepth;
layout(rgba32f, binding = BINDING_OUTPUT_IMAGE) uniform writeonly image2D uOut;
uniform ivec2 uLowSize;
uniform int uDownsample;
uniform float uDepthSigma;
uniform vec3 uBackground;
uniform float uMinTransmittance;

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, ivec2(uSize)))) return;
  vec3 dir = cameraRay(vec2(p) + 0.5);
  float t0, t1;
  float hitT = surfaceDistance(p);
  float depth = !isinf(hitT)                                          ? hitT
                : intersectBox(uEye, dir, 0.0, kInf, t0, t1) && t1 > t0 ? t1
                                                                        : kInf;
  float d = float(uDownsample);
  vec2 l = (vec2(p) + 0.5) / d - 0.5;
  int i0 = clamp(int(floor(l.x)), 0, uLowSize.x - 1), j0 = clamp(int(floor(l.y)), 0, uLowSize.y - 1);
  int i1 = min(i0 + 1, uLowSize.x - 1), j1 = min(j0 + 1, uLowSize.y - 1);
  float fx = clamp(l.x - float(i0), 0.0, 1.0), fy = clamp(l.y - float(j0), 0.0, 1.0);
  ivec2 q[4] = ivec2[4](ivec2(i0, j0), ivec2(i1, j0), ivec2(i0, j1), ivec2(i1, j1));
  float b[4] = float[4]((1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy);
  float w[4];
  float sum = 0.0, nearestDiff = kInf;
  int nearest = 0;
  for (int c = 0; c < 4; ++c) {
    float di = imageLoad(uLowDepth, q[c]).r;
    float diff = di == depth ? 0.0 : abs(di - depth);
    float sim = diff == 0.0 ? 1.0 : (isinf(diff) || isinf(depth)) ? 0.0
                                   : exp(-diff / (uDepthSigma * depth));
    w[c] = b[c] * sim;
    sum += w[c];
    if (diff < nearestDiff) {
      nearestDiff = diff;
      nearest = c;
    }
  }
  vec3 L = vec3(0.0);
  float T = 0.0;
  for (int c = 0; c < 4; ++c) {
    float wc = sum < 1e-6 ? (c == nearest ? 1.0 : 0.0) : w[c] / sum;
    vec4 v = imageLoad(uLow, q[c]);
    L += wc * v.rgb;
    T += wc * v.a;
  }
#ifdef SL_OBJECTS
  if (!isinf(hitT)) {
    vec3 lp = texelFetch(uSurfaceRadiance, p, 0).rgb;
    imageStore(uOut, p, vec4(T > uMinTransmittance ? L + T * lp : L, 0.0));
    return;
  }
#endif
  imageStore(uOut, p, vec4(L + T * uBackground, T));
}
