// froxel, light_transmittance = map (cpu/froxel.cpp, TransmittanceMaps): voxel centre x of
// light l's map holds e^(−σt·τ(x → l)), whether or not x is inside a spot's cone. The maps are
// stacked along z: voxel (i, j, l·R + k).
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(r32f, binding = BINDING_TRANSMITTANCE_MAP_IMAGE) uniform writeonly image3D uMap;
uniform int uMapRes;

void main() {
  ivec3 v = ivec3(gl_GlobalInvocationID);
  if (v.x >= uMapRes || v.y >= uMapRes || v.z >= uMapRes * uLightCount) return;
  int li = v.z / uMapRes;
  // Grid3::cellCenter as the CPU rounds it (cpuDiv, `precise`).
  precise vec3 extent = uBoxMax - uBoxMin;
  vec3 cell = cpuDiv(extent, float(uMapRes));
  precise vec3 x = uBoxMin + (vec3(v.x, v.y, v.z - li * uMapRes) + 0.5) * cell;
  GpuLight l = lights[li];
  vec3 toLight;
  float dist, dist2, cone;
  float value = 0.0;
  if (lightGeometry(l, x, true, toLight, dist, dist2, cone)) {
    value = exp(-uSigmaT * opticalDepth(x, lightSegmentEnd(l, x, toLight, dist), uDelta1));
#ifdef SL_OBJECTS
    value *= lightVisibility(li, x);  // the shadow maps (the CPU: 0 where an object blocks)
#endif
  }
  imageStore(uMap, v, vec4(value));
}
