// The radiance leaving scene-object surfaces towards the camera, per pixel (the twin of
// SurfaceRadiance, shading/transport.h): L_p = albedo/π·Σ_l E_l(p)·max(0, n_s·ω_l)·V_l(p)·T(p, l),
// the light in front of the geometric face too, V_l from the shadow maps (shadow.glsl),
// T marched through the density with step uDelta1 from p moved off the surface by
// uSurfaceOffset along n. Alpha 0: the slice marcher's transmittance channel becomes 0
// (opaque). Also the view-ray distance of p, where the slice marcher's rays end.
in vec3 vWorld;
in vec3 vNormal;
in vec3 vShading;
in vec3 vAlbedo;
uniform float uSurfaceOffset;  // SceneObjects::epsilon()
layout(location = 0) out vec4 outColor;
layout(location = 1) out float outDistance;

void main() {
  vec3 toEye = uEye - vWorld;
  float dist = length(toEye);
  vec3 dir = -toEye / max(dist, 1e-30);  // the camera ray's direction
  vec3 n = normalize(vNormal);
  if (dot(n, dir) > 0.0) n = -n;  // faces the viewer (two-sided surfaces)
  vec3 ns = normalize(vShading);
  if (dot(ns, n) < 0.0) ns = -ns;
  outDistance = dist;
  vec3 e = vec3(0.0);
  if (any(greaterThan(vAlbedo, vec3(0.0)))) {
    vec3 p = vWorld + n * uSurfaceOffset;
    for (int li = 0; li < uLightCount; ++li) {
      GpuLight l = lights[li];
      vec3 toLight;
      float d, d2, cone;
      if (!lightGeometry(l, p, true, toLight, d, d2, cone) || cone <= 0.0) continue;
      float cosine = dot(ns, toLight);
      if (cosine <= 0.0 || dot(n, toLight) <= 0.0) continue;
      float vis = surfaceVisibility(li, p, n);
      if (vis <= 0.0) continue;
      bool sun = int(l.positionType.w) == 2;
      vec3 irradiance = sun ? l.intensityCosOuter.rgb : l.intensityCosOuter.rgb * (cone / d2);
      vec3 segEnd = sun ? boxExit(p, toLight) : p + toLight * d;
      e += irradiance * (cosine * vis * exp(-uSigmaT * opticalDepth(p, segEnd, uDelta1)));
    }
  }
  outColor = vec4(vAlbedo * e * (1.0 / 3.14159265358979323846), 0.0);
}
