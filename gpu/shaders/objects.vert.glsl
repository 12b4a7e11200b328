// Scene-object triangles, attribute-less: corner gl_VertexID of gpu::ObjectGeometry's buffer
// (gpu/objects.h), projected by uViewProj (world -> clip).
// Mirrored by gpu::GpuObjectVertex; std430 offsets 0, 16, 32, 48, stride 64.
struct ObjectVertex {
  vec4 positionObject;  // xyz world position, w object index
  vec4 normal;          // xyz geometric normal
  vec4 shading;         // xyz shading normal
  vec4 albedo;          // rgb
};
layout(std430, binding = BINDING_OBJECT_VERTICES) readonly buffer ObjectVertices {
  ObjectVertex objectVertices[];
};
uniform mat4 uViewProj;
out vec3 vWorld;
out vec3 vNormal;
out vec3 vShading;
out vec3 vAlbedo;

void main() {
  ObjectVertex v = objectVertices[gl_VertexID];
  vWorld = v.positionObject.xyz;
  vNormal = v.normal.xyz;
  vShading = v.shading.xyz;
  vAlbedo = v.albedo.rgb;
  gl_Position = uViewProj * vec4(vWorld, 1.0);
}
