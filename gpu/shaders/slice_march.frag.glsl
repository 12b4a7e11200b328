// Slice-based ray marching (paper Sec. 6). One slab of view depth [uDepthNear, uDepthFar]
// (perpendicular to the view direction) per draw, drawn far to near with blending
// GL_ONE / GL_SRC_ALPHA: dst = rgb + alpha·dst. Per pixel, the slab's piece of the camera ray
// is clipped to the box and treated as the CPU marcher treats one step:
// rgb = Ω·(1 − a)·S(x_mid), a = exp(−σt·D(x_mid)·Δt). With SL_OBJECTS the ray ends at the
// first object surface (gpu::SliceMarcher's surface pass).
layout(binding = BINDING_RADIANCE_TEXTURE) uniform sampler3D uRadiance;
uniform vec3 uRadScale;   // world -> radiance index
uniform vec3 uRadOffset;
uniform ivec3 uRadDims;
uniform vec3 uForward;
uniform vec3 uRight;
uniform vec3 uUp;
uniform vec2 uTanHalf;    // (tan(fov/2)·aspect, tan(fov/2))
uniform vec2 uSize;       // image width, height
uniform float uDepthNear;
uniform float uDepthFar;
uniform float uAlbedo;
uniform int uLayer;      // SL_RAY_STEPS: layer index counted from the far end
uniform float uStep;     // SL_RAY_STEPS: the CPU marcher's step
#ifdef SL_OBJECTS
// View-ray distance of the first object surface per pixel (3e38: none), from the surface pass.
layout(binding = BINDING_SURFACE_TEXTURE) uniform sampler2D uSurfaceDistance;
#endif
layout(location = 0) out vec4 outColor;

void main() {
  // GL row r is image row r (row 0 at the top once read back without flipping).
  vec2 pix = gl_FragCoord.xy;  // (px + 0.5, py + 0.5)
  // The camera's ray as the CPU rounds it (cpu_arithmetic.glsl).
  vec3 dir = cpuCameraRay(pix, uSize, uForward, uRight, uUp, uTanHalf);
  float t0, t1;
  if (!intersectBox(uEye, dir, 0.0, kInf, t0, t1) || !(t1 > t0)) discard;
#ifdef SL_OBJECTS
  // The march stops at the first surface (its L_p is in the framebuffer already).
  t1 = min(t1, texelFetch(uSurfaceDistance, ivec2(gl_FragCoord.xy), 0).r);
  if (!(t1 > t0)) discard;
#endif
#ifdef SL_RAY_STEPS
  // Variant: layer k is step n-1-k of this pixel's ray, exactly the CPU marcher's steps
  // (same sample points), still composited far to near with the same blending.
  int n = stepCount(t1 - t0, uStep);
  int i = n - 1 - uLayer;
  if (i < 0) discard;
  float dt = cpuDiv(t1 - t0, float(n));
  precise float tMid = t0 + (float(i) + 0.5) * dt;
  precise vec3 x = uEye + dir * tMid;
#else
  float c = dot(dir, uForward);
  float a = max(t0, uDepthNear / c), b = min(t1, uDepthFar / c);
  if (!(b > a)) discard;
  float dt = b - a;
  float tMid = 0.5 * (a + b);
  vec3 x = uEye + dir * tMid;
#endif
  float D = densityAtIndex(x * uDensityScale + uDensityOffset);
  if (!(D > 0.0)) discard;
  float alpha = stepTransmittance(uSigmaT * D * dt);
  vec3 S = textureLod(uRadiance, (x * uRadScale + uRadOffset + 0.5) / vec3(uRadDims), 0.0).rgb;
#ifdef SL_FACTOR_LIGHTS
  // The volume holds V = S / A (V = 0: S = 0); A over the step, the glow's substeps included.
  if (S != vec3(0.0)) S *= lightFactorStep(uEye, dir, tMid, dt);
#endif
  outColor = vec4(uAlbedo * (1.0 - alpha) * S, alpha);
}
