// One triangle covering the viewport. With SL_OBJECTS (the slice marcher over scene objects)
// it lies at NDC depth uSlabNdcZ, so that the depth test culls layers behind the surfaces.
#ifdef SL_OBJECTS
uniform float uSlabNdcZ;
#else
const float uSlabNdcZ = 0.0;
#endif
void main() {
  vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  gl_Position = vec4(p * 2.0 - 1.0, uSlabNdcZ, 1.0);
}
