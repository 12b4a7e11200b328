// The cell samplers' occupancy on the GPU (Frame::countOccupiedCells, core/stages.h; GpuFrame):
// several grids counted in one pass, one invocation per density voxel. A voxel with D > 0 sets
// its cell's bit in each grid's bit set, and the bit that changes counts the cell. The
// voxel-centre → cell maps of the three axes of every grid come from the host (voxelCells()),
// so the cells are the CPU's to the bit. The host reads the counts (4 bytes per grid) and, for
// the grid it chooses, that grid's bits: never the volume.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(binding = BINDING_DENSITY_TEXTURE) uniform sampler3D uDensity;
// Per grid g: cellOf[maps + u] for x, then y (from uVoxels.x), then z (from uVoxels.x + uVoxels.y),
// with maps = g · (uVoxels.x + uVoxels.y + uVoxels.z).
layout(std430, binding = BINDING_SAMPLES) readonly buffer CellMaps { int cellOf[]; };
// Per grid: its dims (xyz) and the first word of its bit set (w).
layout(std430, binding = BINDING_OFFSETS) readonly buffer Grids { ivec4 grids[]; };
layout(std430, binding = BINDING_IN_SET) buffer Bits { uint bits[]; };
layout(std430, binding = BINDING_COUNTERS) buffer Occupied { uint occupied[]; };
uniform ivec3 uVoxels;  // the density's dims
uniform int uGrids;     // how many grids

#ifdef SL_VOXEL_COUNTS
// Frame::occupiedVoxelsPerCell: one grid (uGrids 1, its maps at 0), and per cell how many of its
// voxels hold density, in occupied[] (zeroed by the host).
void main() {
  ivec3 u = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(u, uVoxels))) return;
  if (!(texelFetch(uDensity, u, 0).r > 0.0)) return;
  ivec4 grid = grids[0];
  uint c = uint(cellOf[u.x]) + uint(grid.x) * (uint(cellOf[uVoxels.x + u.y]) +
                                               uint(grid.y) * uint(cellOf[uVoxels.x + uVoxels.y + u.z]));
  atomicAdd(occupied[c], 1u);
}
#else
void main() {
  ivec3 u = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(u, uVoxels))) return;
  if (!(texelFetch(uDensity, u, 0).r > 0.0)) return;
  int perGrid = uVoxels.x + uVoxels.y + uVoxels.z;
  for (int g = 0; g < uGrids; ++g) {
    ivec4 grid = grids[g];
    int m = g * perGrid;
    uint c = uint(cellOf[m + u.x]) +
             uint(grid.x) * (uint(cellOf[m + uVoxels.x + u.y]) +
                             uint(grid.y) * uint(cellOf[m + uVoxels.x + uVoxels.y + u.z]));
    uint word = uint(grid.w) + c / 32u, bit = 1u << (c % 32u);
    // Most voxels find their cell's bit set already: the atomic only where it is not.
    if ((bits[word] & bit) == 0u && (atomicOr(bits[word], bit) & bit) == 0u)
      atomicAdd(occupied[g], 1u);
  }
}
#endif
