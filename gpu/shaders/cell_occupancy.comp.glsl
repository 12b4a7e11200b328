// The cell samplers' occupancy on the GPU (Frame::occupiedCells, core/stages.h; GpuFrame): one
// invocation per density voxel; a voxel with D > 0 stamps its cell with this call's token, and
// the stamp that changes a cell counts it. The voxel-centre → cell maps of the three axes come
// from the host (voxelCells()), so the cells are the CPU's to the bit. The host reads the count
// (4 bytes), and for the chosen grid the stamps: never the volume.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(binding = BINDING_DENSITY_TEXTURE) uniform sampler3D uDensity;
// cellOf[u] for x, then y (from uVoxels.x), then z (from uVoxels.x + uVoxels.y)
layout(std430, binding = BINDING_SAMPLES) readonly buffer CellMaps { int cellOf[]; };
layout(std430, binding = BINDING_IN_SET) buffer Stamps { uint stamps[]; };
layout(std430, binding = BINDING_COUNTERS) buffer Occupied { uint occupied; };
uniform ivec3 uVoxels;  // the density's dims
uniform ivec3 uCells;   // the grid's dims
uniform uint uToken;    // this call's stamp (never 0; the buffer starts at 0)

void main() {
  ivec3 u = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(u, uVoxels))) return;
  if (!(texelFetch(uDensity, u, 0).r > 0.0)) return;
  uint c = uint(cellOf[u.x]) +
           uint(uCells.x) * (uint(cellOf[uVoxels.x + u.y]) +
                             uint(uCells.y) * uint(cellOf[uVoxels.x + uVoxels.y + u.z]));
  if (atomicExchange(stamps[c], uToken) != uToken) atomicAdd(occupied, 1u);
}
