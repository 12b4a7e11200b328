// Dynamic sampling, compaction: every vertex of G_{k+1} in the set goes to slot offsets[v]
// (exclusive scan of inSet) of the next level's sample list, with its position (the vertex,
// gridVertex of grid_vertex.glsl), the level's valid radius and its ancestor. Ascending vertex
// order.
// Slots at or past the level's capacity are dropped (the count pass of dynamic_level.comp.glsl records the overflow).
layout(local_size_x = 256) in;

layout(std430, binding = BINDING_IN_SET) readonly buffer InSet { uint inSet[]; };
layout(std430, binding = BINDING_VERTEX_ANCESTORS) readonly buffer VertexAncestor { int vertexAncestor[]; };
layout(std430, binding = BINDING_OFFSETS) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = BINDING_NEXT_SAMPLES) writeonly buffer NextSamples { vec4 nextSamples[]; };
layout(std430, binding = BINDING_NEXT_ANCESTORS) writeonly buffer NextAncestors { int nextAncestors[]; };

uniform uint uVertexCount;
uniform float uRadius;
uniform uint uCapacity;

void main() {
  uint v = SL_LINEAR_INVOCATION;
  if (v >= uVertexCount || inSet[v] == 0u) return;
  uint o = offsets[v];
  if (o >= uCapacity) return;
  nextSamples[o] = vec4(gridVertex(v), uRadius);
  nextAncestors[o] = vertexAncestor[v];
}
