// The vertices of dynamic sampling's grid G_{k+1} (GridInfoBuffer::vertex,
// sampling/dynamic_sampling.h: vertex v = i + nx·(j + ny·k) lies at min + (ijk + 1/2)·interval,
// in float arithmetic as written): where compaction and the top-up place a grid's samples.
uniform vec3 uGridMin;
uniform vec3 uGridInterval;
uniform ivec3 uGridDims;

vec3 gridVertex(uint v) {
  uint nx = uint(uGridDims.x), ny = uint(uGridDims.y);
  uint i = v % nx, j = (v / nx) % ny, k = v / (nx * ny);
  precise vec3 q = uGridMin + (vec3(float(i), float(j), float(k)) + 0.5) * uGridInterval;
  return q;
}
