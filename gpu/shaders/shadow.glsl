// Visibility of the scene's lights through scene objects from shadow maps (gpu/shadow_maps.h,
// docs/objects.md): the GPU's V_l of DESIGN.md §2. Include before common.glsl; with
// SL_OBJECTS, common.glsl multiplies each light's term by lightVisibility(light, x).
//   float lightVisibility(int light, vec3 worldPos)                 points in the medium
//   float surfaceVisibility(int light, vec3 worldPos, vec3 normal)  points on surfaces
// 1 lit, 0 shadowed, in between in a filtered penumbra. `light` indexes lights[] of
// common.glsl (the scene's lights, in order). Needs gpu::ShadowMaps::bind().
#ifdef SL_OBJECTS

// Mirrored by gpu::GpuShadowLight (gpu/shadow_maps.h); std430 offsets 0, 16, 32, stride 48.
struct ShadowLight {
  ivec4 info;      // x first layer (-1: no map), y kind: 0 cube, 1 perspective, 2 orthographic
  vec4 origin;     // xyz light position or orthographic eye; w texel size (per unit distance)
  vec4 direction;  // xyz orthographic: the light's travel direction
};
layout(std430, binding = BINDING_SHADOW_LIGHTS) readonly buffer ShadowLights {
  ShadowLight shadowLights[];
};
// World -> clip of each layer (a cube's six faces are consecutive layers +x, -x, +y, -y, +z, -z).
layout(std430, binding = BINDING_SHADOW_MATRICES) readonly buffer ShadowMatrices {
  mat4 shadowMatrices[];
};
// RG32F moments (d, d²) of the nearest surface's distance metric per texel.
layout(binding = BINDING_SHADOW_TEXTURE) uniform sampler2DArray uShadowMaps;
uniform int uShadowMode;        // 0 vsm, 1 depth compare
uniform float uShadowBias;      // texels
uniform int uShadowFilter;      // depth compare: PCF width (odd); vsm: blurred already
uniform float uShadowBleed;     // vsm light-bleeding reduction
uniform float uShadowResolution;

// The layer, map coordinates, metric d and texel size of point p for light `light`; false
// when p falls outside the map (nothing drawn there can shadow it).
bool shadowLookup(int light, vec3 p, out int layer, out vec2 uv, out float d, out float texel) {
  ShadowLight s = shadowLights[light];
  layer = s.info.x;
  if (layer < 0) return false;
  if (s.info.y == 2) {
    d = dot(p - s.origin.xyz, s.direction.xyz);
    texel = s.origin.w;
  } else {
    vec3 v = p - s.origin.xyz;
    d = length(v);
    texel = s.origin.w * d;
    if (s.info.y == 0) {
      vec3 a = abs(v);
      int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
      layer += 2 * axis + (v[axis] < 0.0 ? 1 : 0);
    }
  }
  vec4 c = shadowMatrices[layer] * vec4(p, 1.0);
  if (!(c.w > 0.0)) return false;
  uv = c.xy / c.w * 0.5 + 0.5;
  return all(greaterThanEqual(uv, vec2(0.0))) && all(lessThanEqual(uv, vec2(1.0)));
}

float shadowVisibilityAt(int layer, vec2 uv, float d, float texel) {
  float z = d - uShadowBias * texel;
  if (uShadowMode == 1) {
    int res = int(uShadowResolution);
    ivec2 c = ivec2(min(uv * uShadowResolution, vec2(uShadowResolution - 1.0)));
    int r = uShadowFilter / 2;
    float lit = 0.0;
    for (int j = -r; j <= r; ++j)
      for (int i = -r; i <= r; ++i) {
        ivec2 t = clamp(c + ivec2(i, j), ivec2(0), ivec2(res - 1));
        lit += z <= texelFetch(uShadowMaps, ivec3(t, layer), 0).r ? 1.0 : 0.0;
      }
    return lit / float((2 * r + 1) * (2 * r + 1));
  }
  vec2 m = textureLod(uShadowMaps, vec3(uv, float(layer)), 0.0).rg;
  if (z <= m.x) return 1.0;
  float variance = max(m.y - m.x * m.x, 0.25 * texel * texel);
  float e = z - m.x;
  float p = variance / (variance + e * e);
  return clamp((p - uShadowBleed) / (1.0 - uShadowBleed), 0.0, 1.0);
}

float lightVisibility(int light, vec3 p) {
  int layer;
  vec2 uv;
  float d, texel;
  if (!shadowLookup(light, p, layer, uv, d, texel)) return 1.0;
  return shadowVisibilityAt(layer, uv, d, texel);
}

float surfaceVisibility(int light, vec3 p, vec3 n) {
  int layer;
  vec2 uv;
  float d, texel;
  if (!shadowLookup(light, p, layer, uv, d, texel)) return 1.0;
  // Normal offset: move one bias along n and look up again there.
  vec3 q = p + n * (uShadowBias * texel);
  if (!shadowLookup(light, q, layer, uv, d, texel)) return 1.0;
  return shadowVisibilityAt(layer, uv, d, texel);
}

#else

float lightVisibility(int light, vec3 p) { return 1.0; }
float surfaceVisibility(int light, vec3 p, vec3 n) { return 1.0; }

#endif
