// Box blur of VSM moments along one axis (uAxis 0: x, 1: y), radius uRadius texels, clamped
// at the map's edges; one invocation per texel of one layer (z = layer).
layout(local_size_x = 8, local_size_y = 8) in;
layout(rg32f, binding = BINDING_BLUR_SOURCE) uniform readonly image2DArray uSource;
layout(rg32f, binding = BINDING_BLUR_TARGET) uniform writeonly image2DArray uTarget;
uniform int uAxis;
uniform int uRadius;
uniform int uResolution;

void main() {
  ivec3 t = ivec3(gl_GlobalInvocationID);
  if (t.x >= uResolution || t.y >= uResolution) return;
  vec2 sum = vec2(0.0);
  for (int k = -uRadius; k <= uRadius; ++k) {
    ivec3 s = t;
    s[uAxis] = clamp(t[uAxis] + k, 0, uResolution - 1);
    sum += imageLoad(uSource, s).rg;
  }
  imageStore(uTarget, t, vec4(sum / float(2 * uRadius + 1), 0.0, 0.0));
}
