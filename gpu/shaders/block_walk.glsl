// MaxDensityGrid::Walk (core/max_density_grid.h) in GLSL: the blocks of SL_BLOCK³ voxels along a
// march u_i = u0 + i·du (index coordinates of the density), i in [0, n), walked with a 3D DDA
// (Amanatides & Woo) in step units. A block whose maximum (uBlockMax, gpu/empty_space.h) is 0
// returns 0 at every lookup of its steps (the grid's one-voxel margin covers the rounding of
// u0 + i·du), so a march that jumps over those steps sums exactly what the plain march sums.
// Needs no other file.
layout(binding = BINDING_BLOCK_MAX_TEXTURE) uniform sampler3D uBlockMax;
uniform ivec3 uBlocks;

struct BlockWalk {
  vec3 u0, inv, next;
  ivec3 b, dir;
  int n;
};

// Where the march leaves the current block along axis a (step units): infinity when it moves
// away from that face's neighbour or the neighbour is outside the grid.
float blockExit(BlockWalk w, int a) {
  int nb = w.b[a] + w.dir[a];
  if (w.dir[a] == 0 || nb < 0 || nb >= uBlocks[a]) return 1.0 / 0.0;
  return (float((w.dir[a] > 0 ? nb : w.b[a]) * int(SL_BLOCK)) - w.u0[a]) * w.inv[a];
}

BlockWalk blockWalk(vec3 u0, vec3 du, int n) {
  BlockWalk w;
  w.u0 = u0;
  w.n = n;
  for (int a = 0; a < 3; ++a) {
    float c = u0[a] > 0.0 ? u0[a] * (1.0 / SL_BLOCK) : 0.0;  // also maps NaN to block 0
    w.b[a] = int(min(c, float(uBlocks[a] - 1)));
    w.dir[a] = du[a] > 0.0 ? 1 : du[a] < 0.0 ? -1 : 0;
    w.inv[a] = w.dir[a] != 0 ? 1.0 / du[a] : 0.0;
  }
  for (int a = 0; a < 3; ++a) w.next[a] = blockExit(w, a);
  return w;
}

// The block of step i (i at or after the previous call's): steps [i, end) stay in it, and
// `empty` says its maximum is zero.
int blockSpan(inout BlockWalk w, int i, out bool empty) {
  for (;;) {
    int a = w.next.x <= w.next.y ? (w.next.x <= w.next.z ? 0 : 2) : (w.next.y <= w.next.z ? 1 : 2);
    if (w.next[a] > float(i)) break;
    w.b[a] += w.dir[a];
    w.next[a] = blockExit(w, a);
  }
  float t = min(min(w.next.x, w.next.y), min(w.next.z, float(w.n)));
  int end = int(t);
  if (float(end) < t) ++end;
  empty = !(texelFetch(uBlockMax, w.b, 0).r > 0.0);
  return min(w.n, max(i + 1, end));
}
