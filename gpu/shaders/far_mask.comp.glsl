// The lights a step of A's far field must evaluate, per brick of SL_FAR_BRICK³ cells of the grid
// (common.glsl lightFactorStep under SL_FAR_FIELD): bit l % 32 of word l / 32 of brick b set for
// every spot and directional light (never in the far field) and for each point light within 2R of
// the brick's cells widened by a cell (a step's midpoint lies in its brick's cells, the widening
// covers rounding): a step then tests the few lamps near it, not every light. One invocation per
// brick, bricks x fastest, uMaskWords words each.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(std430, binding = BINDING_FAR_MASK_OUT) writeonly buffer FarMaskOut { uint farMaskOut[]; };
uniform float uMaskR;
uniform vec3 uMaskLo;
uniform vec3 uMaskCell;
uniform ivec3 uMaskBricks;
uniform int uMaskWords;

void main() {
  ivec3 b = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(b, uMaskBricks))) return;
  const int kBrick = int(SL_FAR_BRICK);
  vec3 lo = uMaskLo + vec3(b * kBrick - 1) * uMaskCell;
  vec3 hi = uMaskLo + vec3(b * kBrick + kBrick + 1) * uMaskCell;
  int base = ((b.z * uMaskBricks.y + b.y) * uMaskBricks.x + b.x) * uMaskWords;
  for (int w = 0; w < uMaskWords; ++w) {
    uint bits = 0u;
    for (int k = 0; k < 32; ++k) {
      int li = w * 32 + k;
      if (li >= uLightCount) break;
      vec3 p = lights[li].positionType.xyz;
      if (int(lights[li].positionType.w) != 0 || length(p - clamp(p, lo, hi)) < 2.0001 * uMaskR)
        bits |= 1u << uint(k);
    }
    farMaskOut[base + w] = bits;
  }
}
