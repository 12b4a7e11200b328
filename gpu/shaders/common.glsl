// Shared by every stage that traces source radiance (DESIGN.md §2). Mirrors, line for line,
// core/light.h (Light::geometry, incident, spotFalloff), core/phase.h (Phase::evalCos), core/math.h
// (Box::intersect, smoothStep), core/grid.h (Grid3::sampleIndex) and shading/transport.h
// (opticalDepth, lightSegmentEnd, SourceRadiance); tests/gpu holds them in step (CPU == GPU).
// With SL_OBJECTS (scene objects), shadow.glsl must be compiled with it: each light's term is
// multiplied by its shadow-map visibility lightVisibility(light, x), the GPU's V_l.

const float kInvFourPi = 1.0 / (4.0 * 3.14159265358979323846);

#ifdef SL_OBJECTS
// Defined by shadow.glsl, compiled into the same program (before or after this file).
float lightVisibility(int light, vec3 worldPos);
#endif
const float kInf = 1.0 / 0.0;

// One light: type 0 point, 1 spot, 2 directional (Light::Type order). Mirrored by gpu::GpuLight
// (gpu/records.h); std430 offsets 0, 16, 32, stride 48.
struct GpuLight {
  vec4 positionType;       // xyz position, w type
  vec4 directionCosInner;  // xyz direction (unit), w cos of the inner half-angle
  vec4 intensityCosOuter;  // rgb intensity / irradiance, w cos of the outer half-angle
  vec4 lamp;  // x: k_l of the lamp model, y (lights[0]): min_l m_l (lamp_k.comp.glsl);
              // z: the glow's substep scale kGlowRatio / w (lightFactorStep); w unused
};
layout(std430, binding = BINDING_LIGHTS) readonly buffer Lights { GpuLight lights[]; };
uniform int uLightCount;
uniform int uPhaseType;  // 0 isotropic, 1 Henyey-Greenstein
uniform float uPhaseG;
uniform float uSigmaT;
uniform float uDelta1;

// S and the rows of ∇S of one sample (rgb; w unused), as the volume tracer and dynamic sampling
// write them. Mirrored by gpu::GpuRadianceRecord (gpu/records.h); std430 offsets S 0, dS 16
// (stride 16), record stride 64.
struct RadianceRecord {
  vec4 S;
  vec4 dS[3];
};

// Density volume: texture unit BINDING_DENSITY_TEXTURE, lookups in index space u (voxel centre i at u = i).
layout(binding = BINDING_DENSITY_TEXTURE) uniform sampler3D uDensity;
uniform vec3 uBoxMin;
uniform vec3 uBoxMax;
uniform vec3 uDensityScale;   // world -> index: u = p * scale + offset
uniform vec3 uDensityOffset;
uniform ivec3 uDensityDims;

float smoothStepCpu(float x, float e0, float e1) {
  if (e0 == e1) return x < e0 ? 0.0 : 1.0;
  float t = clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}
// smoothStep in the CPU's arithmetic (cpuDiv, `precise`): a spot's cone factor at a sample.
float smoothStepExact(float x, float e0, float e1) {
  if (e0 == e1) return x < e0 ? 0.0 : 1.0;
  precise float t = clamp(cpuDiv(x - e0, e1 - e0), 0.0, 1.0);
  precise float r = t * t * (3.0 - 2.0 * t);
  return r;
}

// exp(−x) for one march step's optical depth x ≥ 0, to float rounding near 1 as the CPU's
// std::exp. GLSL lets exp err by 3 + 2|x| ulp (~2e-7 absolute near 1; NVIDIA's ex2.approx
// likewise): at steps of σt·D·Δt ~ 1e-6 that was a fifth of 1 − a and images went dark at the
// short end of march_step's range (issue 37: march_step 2e-5, 88 % off). Below 1/8, 1 − x + x²/2 −
// … to x⁶ (remainder < x⁷/5040 < 5e-10), rounded once.
float stepTransmittance(float x) {
  if (x < 0.125)
    return 1.0 - x * (1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0 -
                                                                               x / 720.0)))));
  return exp(-x);
}

float phaseEvalCos(float c) {
  if (uPhaseType == 0) return kInvFourPi;
  float g = uPhaseG;
  float denom = 1.0 + g * g - 2.0 * g * c;
  return kInvFourPi * (1.0 - g * g) / (denom * sqrt(denom));
}

// Box::intersect: slab test; false when the ray misses.
// The CPU's arithmetic (cpuDiv, `precise`: cpu_arithmetic.glsl): a ray's entry and exit decide
// its step count.
bool intersectBox(vec3 o, vec3 d, float tmin, float tmax, out float t0, out float t1) {
  t0 = tmin;
  t1 = tmax;
  for (int a = 0; a < 3; ++a) {
    float inv = cpuDiv(1.0, d[a]);
    precise float tn = (uBoxMin[a] - o[a]) * inv;
    precise float tf = (uBoxMax[a] - o[a]) * inv;
    if (tn > tf) { float s = tn; tn = tf; tf = s; }
    t0 = tn > t0 ? tn : t0;
    t1 = tf < t1 ? tf : t1;
    if (t0 > t1) return false;
  }
  return true;
}


// VoxelOccupancy (cpu/per_voxel.h): whether a density voxel with D > 0 has a trilinear support
// overlapping that of the radiance voxel centred at c with edge `cell` (the range shrunk by 1e-4
// voxel against rounding). The per-voxel pass skips the others; the normalisation counts the
// occupied voxels no sample covers.
bool radianceVoxelOccupied(vec3 c, vec3 cell) {
  ivec3 lo = max(ivec3(floor((c - cell) * uDensityScale + uDensityOffset + 1e-4)), ivec3(0));
  ivec3 hi = min(ivec3(ceil((c + cell) * uDensityScale + uDensityOffset - 1e-4)), uDensityDims - 1);
  for (int k = lo.z; k <= hi.z; ++k)
    for (int j = lo.y; j <= hi.y; ++j)
      for (int i = lo.x; i <= hi.x; ++i)
        if (texelFetch(uDensity, ivec3(i, j, k), 0).r > 0.0) return true;
  return false;
}

// Grid3::sampleIndex. SL_HW_FILTER uses the texture unit's trilinear filter (fast on a GPU,
// limited to 8 fractional bits of weight on most hardware); the default fetches the eight
// neighbours and interpolates in float, as the CPU does.
float densityAtIndex(vec3 u) {
#ifdef SL_HW_FILTER
  return textureLod(uDensity, (u + 0.5) / vec3(uDensityDims), 0.0).r;
#else
  u = clamp(u, vec3(0.0), vec3(uDensityDims - 1));
  ivec3 i0 = min(ivec3(u), uDensityDims - 1);
  ivec3 i1 = min(i0 + 1, uDensityDims - 1);
  vec3 f = u - vec3(i0);
  float c000 = texelFetch(uDensity, i0, 0).r;
  float c100 = texelFetch(uDensity, ivec3(i1.x, i0.y, i0.z), 0).r;
  float c010 = texelFetch(uDensity, ivec3(i0.x, i1.y, i0.z), 0).r;
  float c110 = texelFetch(uDensity, ivec3(i1.x, i1.y, i0.z), 0).r;
  float c001 = texelFetch(uDensity, ivec3(i0.x, i0.y, i1.z), 0).r;
  float c101 = texelFetch(uDensity, ivec3(i1.x, i0.y, i1.z), 0).r;
  float c011 = texelFetch(uDensity, ivec3(i0.x, i1.y, i1.z), 0).r;
  float c111 = texelFetch(uDensity, i1, 0).r;
  float c00 = c000 + (c100 - c000) * f.x;
  float c10 = c010 + (c110 - c010) * f.x;
  float c01 = c001 + (c101 - c001) * f.x;
  float c11 = c011 + (c111 - c011) * f.x;
  float c0 = c00 + (c10 - c00) * f.y;
  float c1 = c01 + (c11 - c01) * f.y;
  return c0 + (c1 - c0) * f.z;
#endif
}

// DensityGrid::sample: the density at a world point, 0 outside the (closed) box, in the CPU's
// operations (the dynamic-sampling passes compare with the CPU sample for sample).
uniform vec3 uDensityInvCell;  // u = (p − min)·invCell − 0.5
float densityAtPoint(vec3 p) {
  if (any(lessThan(p, uBoxMin)) || any(greaterThan(p, uBoxMax))) return 0.0;
  precise vec3 u = (p - uBoxMin) * uDensityInvCell - 0.5;
  return densityAtIndex(u);
}

// opticalDepth(DensityGrid, a, b, step, maxDepth): midpoint rule in index space. With
// SL_SKIP_SHADOWS (gpu::addShadowRaySkip) empty blocks are jumped over, and the sum stops after
// the block where it passes maxDepth (the CPU's shadow rays: shading/transport.h).
float opticalDepth(vec3 a, vec3 b, float stepLen, float maxDepth) {
  // The segment's steps in the CPU's arithmetic (indexSteps): the same n, dt and lookups.
  precise vec3 d = b - a;
  float len = cpuLength(d);
  if (len <= 0.0) return 0.0;
  vec3 dir = cpuDiv(d, len);
  float t0, t1;
  if (!intersectBox(a, dir, 0.0, len, t0, t1) || t1 <= t0) return 0.0;
  int n = stepCount(t1 - t0, stepLen);
  float dt = cpuDiv(t1 - t0, float(n));
  precise vec3 u0 = (a + dir * (t0 + 0.5 * dt)) * uDensityScale + uDensityOffset;
  precise vec3 du = dir * dt * uDensityScale;
  float sum = 0.0;
#ifdef SL_SKIP_SHADOWS
  // The steps in blocks of zero density add exactly 0 (block_walk.glsl, compiled before this
  // file): jumped over, the same sum bit for bit up to maxDepth.
  float sumMax = maxDepth / dt;
  BlockWalk walk = blockWalk(u0, du, n);
  for (int i = 0; i < n && sum <= sumMax;) {
    bool empty;
    int end = blockSpan(walk, i, empty);
    if (!empty)
      for (; i < end; ++i) sum += densityAtIndex(u0 + float(i) * du);
    i = end;
  }
#else
  for (int i = 0; i < n; ++i) sum += densityAtIndex(u0 + float(i) * du);
#endif
  return sum * dt;
}

float opticalDepth(vec3 a, vec3 b, float stepLen) { return opticalDepth(a, b, stepLen, kInf); }

// shadowDepthCutoff(σt) (shading/transport.h): the density integral at which a shadow ray to a
// light stops where empty space is skipped, σt·τ = SL_SHADOW_DEPTH_CUTOFF (exp(−25) ≈ 1.4e-11
// of the light gets through), as the CPU's shadow rays stop.
float shadowDepthCutoff() { return uSigmaT > 0.0 ? SL_SHADOW_DEPTH_CUTOFF / uSigmaT : kInf; }

// Light::spotFalloff in the CPU's arithmetic: spot l's cone factor for the unit direction towards
// it, toLight.
float spotConeExact(GpuLight l, vec3 toLight) {
  return smoothStepExact(cpuDot(-toLight, l.directionCosInner.xyz), l.intensityCosOuter.w,
                         l.directionCosInner.w);
}

// Light::geometry (core/light.h): direction and distance towards light l from x, and the spot
// cone factor (1 for point and directional lights); false only at a point or spot light itself.
// `exact` (a sample's or a voxel's S, a shadow ray's end): in the CPU's arithmetic (cpuSqrt,
// cpuDiv, cpuDot), the same toLight, distance and cone bit for bit; without (A at every view-march
// step, where the result only moves continuously) in the GPU's own, at float speed.
bool lightGeometry(GpuLight l, vec3 x, bool exact, out vec3 toLight, out float dist,
                   out float dist2, out float cone) {
  cone = 1.0;
  if (int(l.positionType.w) == 2) {
    toLight = -l.directionCosInner.xyz;
    dist = dist2 = kInf;
    return true;
  }
  precise vec3 d = l.positionType.xyz - x;
  if (exact) {
    dist2 = cpuDot(d, d);
    if (dist2 <= 0.0) return false;
    dist = cpuSqrt(dist2);
    toLight = cpuDiv(d, dist);
    if (int(l.positionType.w) == 1) cone = spotConeExact(l, toLight);
    return true;
  }
  dist2 = dot(d, d);
  if (dist2 <= 0.0) return false;
  dist = sqrt(dist2);
  toLight = d / dist;
  if (int(l.positionType.w) == 1) {
    float c = dot(-toLight, l.directionCosInner.xyz);
    float cosOuter = l.intensityCosOuter.w, cosInner = l.directionCosInner.w;
    // In a spot's transition an ulp of the cosine moves the cone by up to 1.5 ulp / (cos inner −
    // cos outer), 10⁴ ulps for a 1° spot (the edge-case sweep's spot_1deg: 1.8e-2 relative L2
    // with the built-ins 4 ulps off): there the cosine is the CPU's (cpu_arithmetic.glsl).
    // Outside it the cone is 0 or 1 whatever the rounding, and a step pays no double.
    if (c > cosOuter - 1e-5 && c < cosInner + 1e-5)
      cone = spotConeExact(l, cpuDiv(d, cpuSqrt(cpuDot(d, d))));
    else
      cone = smoothStepCpu(c, cosOuter, cosInner);
  }
  return true;
}

// LitReach::reaches (shading/transport.h), the same formula: whether some light's A may be
// non-zero within r of c. A point or directional light lights everything; a spot its outer
// cone, widened by SL_LIT_MARGIN radians, which the ball (grown by SL_LIT_GROW) meets where
// the angle of c to the axis is at most the cone's plus asin(r / L).
bool litReaches(vec3 c, float r) {
  r *= SL_LIT_GROW;
  for (int li = 0; li < uLightCount; ++li) {
    GpuLight l = lights[li];
    if (int(l.positionType.w) != 1) return true;
    float angle = acos(clamp(l.intensityCosOuter.w, -1.0, 1.0)) + SL_LIT_MARGIN;
    float cosA = cos(angle), sinA = sin(angle);
    vec3 v = c - l.positionType.xyz;
    float L = length(v);
    if (L <= r) return true;
    float sinB = r / L, cosB = sqrt(1.0 - sinB * sinB);
    if (angle > 1.57079633 && sinB >= sinA) return true;
    if (dot(v, l.directionCosInner.xyz) >= L * (cosA * cosB - sinA * sinB)) return true;
  }
  return false;
}

// The end of the segment to trace towards a directional light: where the ray leaves the box.
vec3 boxExit(vec3 x, vec3 toLight) {
  float t0, t1;
  precise vec3 end = x;
  if (intersectBox(x, toLight, 0.0, kInf, t0, t1)) end = x + toLight * t1;
  return end;
}

// lightSegmentEnd (shading/transport.h): the far end of the shadow ray from x towards light l,
// the light itself (x + toLight·dist, as the CPU rounds it) or, for a directional light, where
// the ray leaves the box.
vec3 lightSegmentEnd(GpuLight l, vec3 x, vec3 toLight, float dist) {
  if (int(l.positionType.w) == 2) return boxExit(x, toLight);
  precise vec3 end = x + toLight * dist;
  return end;
}

// SourceRadiance::operator()'s terms for lights li = first, first + stride, … (S at x for
// light leaving towards the viewer along toViewer is their sum over every light; the volume
// tracer splits the lights between invocations and adds the parts in shared memory).
vec3 sourceRadiancePart(vec3 x, vec3 toViewer, int first, int stride) {
  vec3 s = vec3(0.0);
  for (int li = first; li < uLightCount; li += stride) {
    GpuLight l = lights[li];
    vec3 toLight, irradiance, segEnd;
    float dist, dist2, f;
    if (!lightGeometry(l, x, true, toLight, dist, dist2, f) || f <= 0.0) continue;
    irradiance = int(l.positionType.w) == 2 ? l.intensityCosOuter.rgb
                                             : l.intensityCosOuter.rgb * (f / dist2);
    segEnd = lightSegmentEnd(l, x, toLight, dist);
#ifdef SL_OBJECTS
    // V_l through scene objects (shadow.glsl): the CPU skips a blocked light.
    float vis = lightVisibility(li, x);
    if (vis <= 0.0) continue;
#else
    const float vis = 1.0;
#endif
    float tau = opticalDepth(x, segEnd, uDelta1, shadowDepthCutoff());
    s += irradiance * (vis * phaseEvalCos(dot(-toLight, toViewer)) * exp(-uSigmaT * tau));
  }
  return s;
}

// SourceRadiance::operator(): S at x for light leaving towards the viewer along toViewer.
vec3 sourceRadiance(vec3 x, vec3 toViewer) { return sourceRadiancePart(x, toViewer, 0, 1); }

#if defined(SL_LAMP_MODEL) || defined(SL_LAMP_BOUNDS)
const float kLampDepth = SL_LAMP_DEPTH;  // kLampDepth of core/stages.h, injected
// LampModel (shading/transport.h): m_l = exp(−κ·q / (q + κ)), q = k_l·d, k_l = σt·D(s_l) for a
// point or spot light inside the medium's box; 1 otherwise.
// k_l of light li: σt·D(s_l) inside the box, 0 for a directional light or one outside; looked
// up once per lights and density by lamp_k.comp.glsl (gpu::deviceLights), not per light and
// step.
float lampK(int li) { return lights[li].lamp.x; }
// m_l at distance d from a lamp of k_l = k.
float lampModelAt(float k, float d) {
  if (!(k > 0.0)) return 1.0;
  float q = k * d;
  return exp(-kLampDepth * q / (q + kLampDepth));
}
float lampModel(int li, vec3 x) {
  return lampModelAt(lampK(li), length(lights[li].positionType.xyz - x));
}
#endif

// One light's analytic weight, the twin of FactoredSourceRadiance::term (shading/transport.h):
// w = E0·f (cone not applied), the cone factor, and the far end of the segment to trace.
// `exact`: lightGeometry's; without it (A, which traces nothing) segEnd is not set up: the box
// exit's divisions would run at every march step.
bool lightTerm(int li, vec3 x, vec3 toViewer, bool exact, out vec3 w, out float cone,
               out vec3 segEnd) {
  GpuLight l = lights[li];
  vec3 toLight, e0;
  float dist, dist2;
  if (!lightGeometry(l, x, exact, toLight, dist, dist2, cone)) return false;
  if (int(l.positionType.w) == 2) {
    e0 = l.intensityCosOuter.rgb;
    segEnd = exact ? boxExit(x, toLight) : x;
  } else {
    e0 = l.intensityCosOuter.rgb / dist2;
    segEnd = l.positionType.xyz;
  }
  w = e0 * phaseEvalCos(dot(-toLight, toViewer));
  return true;
}

// FactoredSourceRadiance::transmittance: V_l·T towards light li (objects block it; with
// SL_OBJECTS V_l comes from the shadow maps of shadow.glsl).
float lightTransmittance(int li, vec3 x, vec3 segEnd) {
#ifdef SL_OBJECTS
  float vis = lightVisibility(li, x);
  if (vis <= 0.0) return 0.0;
#else
  const float vis = 1.0;
#endif
  return vis * exp(-uSigmaT * opticalDepth(x, segEnd, uDelta1, shadowDepthCutoff()));
}

// LightFactor::operator() (shading/transport.h): A(x, ω), the lights' analytic, unshadowed source
// radiance (singular-light factorization, docs/fidelity.md).
vec3 lightFactor(vec3 x, vec3 toViewer) {
  vec3 a = vec3(0.0);
  for (int li = 0; li < uLightCount; ++li) {
    vec3 w, segEnd;
    float cone;
#ifdef SL_LAMP_MODEL
    if (lightTerm(li, x, toViewer, true, w, cone, segEnd)) a += w * (cone * lampModel(li, x));
#else
    if (lightTerm(li, x, toViewer, true, w, cone, segEnd)) a += w * cone;
#endif
  }
  return a;
}

// One light's term of A at x (lightFactor's).
vec3 lightFactorTerm(int li, vec3 x, vec3 toViewer) {
  vec3 w, segEnd;
  float cone;
  if (!lightTerm(li, x, toViewer, false, w, cone, segEnd)) return vec3(0.0);
#ifdef SL_LAMP_MODEL
  return w * (cone * lampModel(li, x));
#else
  return w * cone;
#endif
}

// The distance from a light at p to the step of length dt centred at x along dir (glowDistance
// of core/stages.h).
float glowDistance(vec3 p, vec3 x, vec3 dir, float dt) {
  vec3 v = p - x;
  float tc = clamp(dot(v, dir), -0.5 * dt, 0.5 * dt);
  return length(v - tc * dir);
}

// glowDistance in the CPU's arithmetic (cpuDot, cpuLength, `precise`).
float glowDistanceExact(vec3 p, vec3 x, vec3 dir, float dt) {
  precise vec3 v = p - x;
  precise float tc = clamp(cpuDot(v, dir), -0.5 * dt, 0.5 * dt);
  precise vec3 w = v - tc * dir;
  return cpuLength(w);
}

// The substeps of a light's glow at a step `dist` from it (glowSubsteps of core/stages.h,
// kGlowRatio and kGlowMaxSubsteps), the ratio in the CPU's arithmetic.
int glowSubsteps(float dist, float reach) {
  if (!(dist < reach)) return 1;
  if (!(dist > 0.0)) return int(SL_GLOW_MAX_SUBSTEPS);
  return int(min(ceil(cpuDiv(reach, dist)), SL_GLOW_MAX_SUBSTEPS));
}

// A's far field (FarField of shading/transport.h): w_l at x, smoothstep(R, 2R, |p_l − x|) for a
// point light (type 0), 0 for the others.
float farWeight(int li, vec3 x, float R) {
  if (int(lights[li].positionType.w) != 0) return 0.0;
  float u = clamp((length(lights[li].positionType.xyz - x) - R) / R, 0.0, 1.0);
  return u * u * (3.0 - 2.0 * u);
}

#ifdef SL_FAR_FIELD
// The grid of far terms Σ_l w_l·A_l (far_field.comp.glsl): texel (i, j, k) of an RGBA32F 3D
// texture is the vertex at uFarLo + (i, j, k) · uFarCell (gpu/bindings.h kFarFieldTexture).
layout(binding = BINDING_FAR_FIELD_TEXTURE) uniform sampler3D uFarField;
uniform float uFarR;
uniform vec3 uFarLo;
uniform vec3 uFarCell;
uniform ivec3 uFarDims;
// The lights a step in each brick of SL_FAR_BRICK³ cells evaluates (far_mask.comp.glsl):
// uFarWords words of bits per brick, bricks x fastest.
layout(std430, binding = BINDING_FAR_MASK) readonly buffer FarMaskGrid { uint farMask[]; };
uniform ivec3 uFarBricks;
uniform int uFarWords;
int farBrick(vec3 x) {
  ivec3 c = ivec3(floor((x - uFarLo) / uFarCell)) / int(SL_FAR_BRICK);
  c = clamp(c, ivec3(0), uFarBricks - 1);
  return (c.z * uFarBricks.y + c.y) * uFarBricks.x + c.x;
}
vec3 farAt(int i, int j, int k) { return texelFetch(uFarField, ivec3(i, j, k), 0).rgb; }
// FarField::lookup: trilinear between the grid's vertices, x clamped into the box.
vec3 farLookup(vec3 x) {
  vec3 u = clamp((x - uFarLo) / uFarCell, vec3(0.0), vec3(uFarDims - ivec3(1)));
  ivec3 b = min(ivec3(floor(u)), uFarDims - ivec3(2));
  vec3 t = u - vec3(b);
  vec3 c00 = mix(farAt(b.x, b.y, b.z), farAt(b.x + 1, b.y, b.z), t.x);
  vec3 c10 = mix(farAt(b.x, b.y + 1, b.z), farAt(b.x + 1, b.y + 1, b.z), t.x);
  vec3 c01 = mix(farAt(b.x, b.y, b.z + 1), farAt(b.x + 1, b.y, b.z + 1), t.x);
  vec3 c11 = mix(farAt(b.x, b.y + 1, b.z + 1), farAt(b.x + 1, b.y + 1, b.z + 1), t.x);
  return mix(mix(c00, c10, t.y), mix(c01, c11, t.y), t.z);
}
#endif

// Light li's term of A over the view march's step of length dt centred at x = origin + t·dir
// (toViewer = −dir): its term at x, or near a point or spot light (the glow) the mean of its term
// at the midpoints of n substeps (the CPU's factorGroup and glowMean, LightFactor::overStep).
uniform float uGlow;  // render.glow: 1 (the glow's substeps), 0 (each step's midpoint only)
vec3 lightStepTerm(int li, vec3 origin, vec3 dir, vec3 x, float t, float dt) {
  int n = 1;
  if (int(lights[li].positionType.w) != 2) {
    float reach = lights[li].lamp.z * dt * uGlow;
    float d = glowDistance(lights[li].positionType.xyz, x, dir, dt);
    // Where the count is decided (near the reach and inside it) the distance is taken in the
    // CPU's arithmetic, so that an ulp does not give the step another count of substeps; the
    // GPU's own is within 1e-6 of it, far inside the margin.
    if (d < reach * 1.001) d = glowDistanceExact(lights[li].positionType.xyz, x, dir, dt);
    n = glowSubsteps(d, reach);
  }
  if (n == 1) return lightFactorTerm(li, x, -dir);
  vec3 s = vec3(0.0);
  for (int m = 0; m < n; ++m)
    s += lightFactorTerm(li, origin + dir * (t + ((float(m) + 0.5) / float(n) - 0.5) * dt), -dir);
  return s / float(n);
}

// A over the view march's step: every light's lightStepTerm. With SL_FAR_FIELD the far field's
// lookup plus each light's near part, (1 − w_l) times its term, for the lights the step's brick
// lists (far_mask.comp.glsl: every spot and directional light, the point lights within 2R of the
// brick), in ascending order as the CPU's sum. The part of lights first, first + stride, … (the
// far field's lookup with the part of first 0): a march split over dispatches where the driver
// caps loops (gpu::lightDispatches) adds the parts; (0, 1) is every light.
vec3 lightFactorStepPart(vec3 origin, vec3 dir, float t, float dt, int first, int stride) {
  precise vec3 x = origin + dir * t;  // Ray::at, as the CPU rounds it
#ifdef SL_FAR_FIELD
  vec3 a = first == 0 ? farLookup(x) : vec3(0.0);
  int base = farBrick(x) * uFarWords;
  for (int w = 0; w < uFarWords; ++w) {
    uint bits = farMask[base + w];
    while (bits != 0u) {
      int li = w * 32 + findLSB(bits);
      bits &= bits - 1u;
      if (li % stride != first) continue;
      float keep = 1.0 - farWeight(li, x, uFarR);
      if (keep > 0.0) a += keep * lightStepTerm(li, origin, dir, x, t, dt);
    }
  }
#else
  vec3 a = vec3(0.0);
  for (int li = first; li < uLightCount; li += stride)
    a += lightStepTerm(li, origin, dir, x, t, dt);
#endif
  return a;
}
vec3 lightFactorStep(vec3 origin, vec3 dir, float t, float dt) {
  return lightFactorStepPart(origin, dir, t, dt, 0, 1);
}

// FactoredSourceRadiance::operator() in parts, for lights li = first, first + stride, … (the
// volume tracer splits the lights between invocations and adds the parts):
// s = Σ w·cone·V_l·T and a = Σ w·cone·m_l over the lights whose cone holds x; `outside` counts
// those whose cone does not (their w and T are not traced unless factoredNeedsFree).
void factoredPart(vec3 x, vec3 toViewer, int first, int stride, out vec3 s, out vec3 a,
                  out float outside) {
  s = vec3(0.0);
  a = vec3(0.0);
  outside = 0.0;
  for (int li = first; li < uLightCount; li += stride) {
    vec3 w, segEnd;
    float cone;
    if (!lightTerm(li, x, toViewer, true, w, cone, segEnd)) continue;
    if (cone <= 0.0) {
      outside += 1.0;
      continue;
    }
    s += w * (cone * lightTransmittance(li, x, segEnd));
#ifdef SL_LAMP_MODEL
    a += w * (cone * lampModel(li, x));
#else
    a += w * cone;
#endif
  }
}
// Where A (a, the sum over every light) is zero in a channel that some light lights while x
// lies outside a cone (outside > 0), V is taken with the cones ignored: the sums of
// factoredFreePart are needed.
bool factoredNeedsFree(vec3 a, float outside) {
  if (!(outside > 0.0)) return false;
  vec3 lit = vec3(0.0);
  for (int li = 0; li < uLightCount; ++li) lit = max(lit, lights[li].intensityCosOuter.rgb);
  for (int c = 0; c < 3; ++c)
    if (!(a[c] > 0.0) && lit[c] > 0.0) return true;
  return false;
}
// The cones-ignored sums sf = Σ w·V_l·T, af = Σ w·m_l for lights first, first + stride, ….
void factoredFreePart(vec3 x, vec3 toViewer, int first, int stride, out vec3 sf, out vec3 af) {
  sf = vec3(0.0);
  af = vec3(0.0);
  for (int li = first; li < uLightCount; li += stride) {
    vec3 w, segEnd;
    float cone;
    if (!lightTerm(li, x, toViewer, true, w, cone, segEnd)) continue;
    sf += w * lightTransmittance(li, x, segEnd);
#ifdef SL_LAMP_MODEL
    af += w * lampModel(li, x);
#else
    af += w;
#endif
  }
}
// V from the sums over every light: s / a per channel; where a is zero, sf / af (sf and af are
// zero unless factoredNeedsFree: a channel no light lights has af = 0 too, so V is 0 there).
vec3 factoredCombine(vec3 s, vec3 a, vec3 sf, vec3 af) {
  vec3 v = vec3(0.0);
  for (int c = 0; c < 3; ++c) {
    if (a[c] > 0.0) v[c] = s[c] / a[c];
    else if (af[c] > 0.0) v[c] = sf[c] / af[c];
  }
  return v;
}

// FactoredSourceRadiance::operator(): V = S / A; where A is zero in a channel (outside every
// cone), V with the cones ignored.
vec3 factoredSource(vec3 x, vec3 toViewer) {
  vec3 s, a, sf = vec3(0.0), af = vec3(0.0);
  float outside;
  factoredPart(x, toViewer, 0, 1, s, a, outside);
  if (factoredNeedsFree(a, outside)) factoredFreePart(x, toViewer, 0, 1, sf, af);
  return factoredCombine(s, a, sf, af);
}

// What the samples hold at p seen from the camera at uEye (per-voxel and evaluator
// convention): S; V = S / A with SL_FACTOR_LIGHTS; ln V (V clamped below at SL_MIN_V, kMinV of
// cpu/radiance_evaluator.h) with SL_LOG_SPACE too.
uniform vec3 uEye;
// The unit direction from p to the camera, (0, 0, 1) at the camera itself.
vec3 towardsEye(vec3 p) {  // in the CPU's arithmetic (once per sample or voxel)
  precise vec3 v = uEye - p;
  float len = cpuLength(v);
  return len > 0.0 ? cpuDiv(v, len) : vec3(0.0, 0.0, 1.0);
}
vec3 sourceTowardsEye(vec3 p) {
  vec3 toViewer = towardsEye(p);
#if defined(SL_FACTOR_LIGHTS) && defined(SL_LOG_SPACE)
  return log(max(factoredSource(p, toViewer), vec3(SL_MIN_V)));
#elif defined(SL_FACTOR_LIGHTS)
  return factoredSource(p, toViewer);
#else
  return sourceRadiance(p, toViewer);
#endif
}

// lightFactorTowardsEye (sampling/dynamic_sampling.cpp): A at p towards the camera, the weight of
// dynamic sampling's error of S = A ⊙ V (SL_WEIGHT_A, ErrorSpace::weightA).
vec3 lightFactorTowardsEye(vec3 p) { return lightFactor(p, towardsEye(p)); }
