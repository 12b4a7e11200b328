// One shadow-map layer (gpu/shadow_maps.h): the moments (d, d²) of the nearest surface's
// distance metric, d = |x − light| (perspective and cube maps) or the depth along the light's
// direction from the orthographic eye.
in vec3 vWorld;
in vec3 vNormal;
in vec3 vShading;
in vec3 vAlbedo;
uniform vec3 uShadowOrigin;
uniform vec3 uShadowDirection;
uniform int uShadowOrtho;
layout(location = 0) out vec2 outMoments;

void main() {
  float d = uShadowOrtho != 0 ? dot(vWorld - uShadowOrigin, uShadowDirection)
                              : length(vWorld - uShadowOrigin);
  outMoments = vec2(d, d * d);
}
