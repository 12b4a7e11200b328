// The residual F of a .sog medium (media/sog.h) on the GPU, uploaded sparsely.
// SL_SCATTER: one invocation per hash entry (key = linear lattice index, x fastest; code):
// F = code · step stored at its cell of the lattice image (cleared to 0 beforehand), as
// ResidualHash::decode.
// Without it: one invocation per voxel of the density volume (the Gaussians already splatted
// into it): d = max(0, d + F(p)) at the voxel centre p, F trilinear between lattice cell centres
// clamped to the outermost ones and 0 outside the lattice box: SogModel::splat operation for
// operation (`precise`).
#ifdef SL_SCATTER
layout(local_size_x = 64) in;
layout(std430, binding = BINDING_RESIDUAL_ENTRIES) readonly buffer Entries { ivec2 entries[]; };
layout(r32f, binding = BINDING_RESIDUAL_IMAGE) writeonly uniform image3D uResidual;
uniform uint uCount;
uniform ivec3 uLatticeDims;
uniform float uStep;

void main() {
  uint e = SL_LINEAR_INVOCATION;
  if (e >= uCount) return;
  uint key = uint(entries[e].x);
  uint nx = uint(uLatticeDims.x), ny = uint(uLatticeDims.y);
  ivec3 c = ivec3(int(key % nx), int((key / nx) % ny), int(key / (nx * ny)));
  precise float f = float(entries[e].y) * uStep;
  imageStore(uResidual, c, vec4(f));
}
#else
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(binding = BINDING_RESIDUAL_TEXTURE) uniform sampler3D uResidualLattice;
layout(r32f, binding = BINDING_DENSITY_IMAGE) uniform image3D uDensityOut;
uniform vec3 uGridMin;
uniform vec3 uGridCell;
uniform ivec3 uGridDims;
uniform vec3 uLatticeMin;
uniform vec3 uLatticeMax;
uniform vec3 uLatticeCell;  // lattice extent / dims, as latticeIndex divides
uniform ivec3 uLatticeDims;
uniform int uHasResidual;   // 0: the hash is empty (F = 0)

float F(int i, int j, int k) { return texelFetch(uResidualLattice, ivec3(i, j, k), 0).r; }

void main() {
  ivec3 v = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(v, uGridDims))) return;
  precise vec3 p = uGridMin + (vec3(v) + 0.5) * uGridCell;
  float d = imageLoad(uDensityOut, v).r;
  precise float f = 0.0;
  if (uHasResidual != 0 && all(greaterThanEqual(p, uLatticeMin)) &&
      all(lessThanEqual(p, uLatticeMax))) {
    ivec3 n = uLatticeDims;
    precise vec3 u = (p - uLatticeMin) / uLatticeCell - 0.5;
    u = clamp(u, vec3(0.0), vec3(n - 1));
    int i0 = min(int(u.x), n.x - 1), j0 = min(int(u.y), n.y - 1), k0 = min(int(u.z), n.z - 1);
    int i1 = min(i0 + 1, n.x - 1), j1 = min(j0 + 1, n.y - 1), k1 = min(k0 + 1, n.z - 1);
    precise float fx = u.x - float(i0), fy = u.y - float(j0), fz = u.z - float(k0);
    precise float c00 = F(i0, j0, k0) + (F(i1, j0, k0) - F(i0, j0, k0)) * fx;
    precise float c10 = F(i0, j1, k0) + (F(i1, j1, k0) - F(i0, j1, k0)) * fx;
    precise float c01 = F(i0, j0, k1) + (F(i1, j0, k1) - F(i0, j0, k1)) * fx;
    precise float c11 = F(i0, j1, k1) + (F(i1, j1, k1) - F(i0, j1, k1)) * fx;
    precise float c0 = c00 + (c10 - c00) * fy;
    precise float c1 = c01 + (c11 - c01) * fy;
    f = c0 + (c1 - c0) * fz;
  }
  imageStore(uDensityOut, v, vec4(max(0.0, d + f)));
}
#endif
