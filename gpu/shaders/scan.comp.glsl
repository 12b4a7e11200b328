// Work-efficient exclusive scan (Blelloch 1990; Harris et al., GPU Gems 3 ch. 39, without the
// bank-conflict padding): each workgroup of 256 invocations scans a block of 512 elements in
// shared memory (up-sweep, clear the root, down-sweep) and writes the block's total to
// blockSums. The host scans blockSums the same way (recursively) and SL_SCAN_ADD adds the
// scanned block sums to every element of the block. With uFlags = 1 the input counts non-zero
// as one (flags -> slots). Blocks past 65 535 span two axes (gpu/dispatch.h linearDispatch).
#define SCAN_BLOCK 512u
layout(local_size_x = 256) in;

uniform uint uCount;

#ifdef SL_SCAN_ADD
layout(std430, binding = BINDING_SCAN_OUT) buffer Out { uint outData[]; };
layout(std430, binding = BINDING_SCAN_SCANNED_SUMS) readonly buffer ScannedSums { uint scannedSums[]; };
void main() {
  uint t = gl_LocalInvocationID.x;
  uint base = SL_LINEAR_GROUP * SCAN_BLOCK;
  if (base >= uCount) return;  // past the last block (linearDispatch's last row)
  uint add = scannedSums[SL_LINEAR_GROUP];
  uint a = base + 2u * t, b = a + 1u;
  if (a < uCount) outData[a] += add;
  if (b < uCount) outData[b] += add;
}
#else
layout(std430, binding = BINDING_SCAN_IN) readonly buffer In { uint inData[]; };
layout(std430, binding = BINDING_SCAN_OUT) writeonly buffer Out { uint outData[]; };
layout(std430, binding = BINDING_SCAN_BLOCK_SUMS) writeonly buffer Sums { uint blockSums[]; };
uniform int uFlags;
shared uint temp[SCAN_BLOCK];

void main() {
  uint t = gl_LocalInvocationID.x;
  uint base = SL_LINEAR_GROUP * SCAN_BLOCK;
  if (base >= uCount) return;  // the whole workgroup: past the last block (linearDispatch)
  uint a = base + 2u * t, b = a + 1u;
  uint va = a < uCount ? inData[a] : 0u;
  uint vb = b < uCount ? inData[b] : 0u;
  if (uFlags != 0) {
    va = va != 0u ? 1u : 0u;
    vb = vb != 0u ? 1u : 0u;
  }
  temp[2u * t] = va;
  temp[2u * t + 1u] = vb;
  uint offset = 1u;
  for (uint d = SCAN_BLOCK >> 1; d > 0u; d >>= 1) {  // up-sweep (reduce)
    memoryBarrierShared();
    barrier();
    if (t < d) {
      uint ai = offset * (2u * t + 1u) - 1u;
      uint bi = offset * (2u * t + 2u) - 1u;
      temp[bi] += temp[ai];
    }
    offset <<= 1;
  }
  memoryBarrierShared();
  barrier();
  if (t == 0u) {
    blockSums[SL_LINEAR_GROUP] = temp[SCAN_BLOCK - 1u];
    temp[SCAN_BLOCK - 1u] = 0u;
  }
  for (uint d = 1u; d < SCAN_BLOCK; d <<= 1) {  // down-sweep
    offset >>= 1;
    memoryBarrierShared();
    barrier();
    if (t < d) {
      uint ai = offset * (2u * t + 1u) - 1u;
      uint bi = offset * (2u * t + 2u) - 1u;
      uint x = temp[ai];
      temp[ai] = temp[bi];
      temp[bi] += x;
    }
  }
  memoryBarrierShared();
  barrier();
  if (a < uCount) outData[a] = temp[2u * t];
  if (b < uCount) outData[b] = temp[2u * t + 1u];
}
#endif
