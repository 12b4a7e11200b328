// Radiance splatting (paper Sec. 4, Eq. 4) as a gather (render.gpu_pipeline = compute;
// gpu::GradientSplatGpu): each voxel centre x sums (W·(S_j + (x − x_j)·∇S_j), W),
// W = R_j/‖x − x_j‖, over the samples whose valid sphere holds it, reading only its bin's list
// (gpu/sphere_bins.h: ascending sample order, the order in which the rasterised splat blends,
// radiance_splat.frag.glsl, whose per-sample arithmetic this mirrors). The sums go to the same
// image the normalisation reads. With SL_OCCLUSION compiled after common.glsl.
// The samples are read as the volume tracer leaves them (struct of arrays): positions and radii
// at BINDING_SAMPLES (gpu::GpuSamplePoint), S and ∇S at BINDING_RADIANCE (gpu::GpuRadianceRecord),
// so the tracer's output is gathered where it was written, with no trip through the host.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

struct GatherRecord { vec4 S; vec4 dS[3]; };  // gpu::GpuRadianceRecord
layout(std430, binding = BINDING_SAMPLES) readonly buffer GatherPoints { vec4 points[]; };
layout(std430, binding = BINDING_RADIANCE) readonly buffer GatherRadiance { GatherRecord records[]; };
layout(std430, binding = BINDING_BIN_OFFSETS) readonly buffer BinOffsets { uint binOffsets[]; };
layout(std430, binding = BINDING_BIN_ITEMS) readonly buffer BinItems { uint binItems[]; };
layout(rgba32f, binding = BINDING_SUMS_IMAGE) uniform writeonly image3D uSums;
uniform vec3 uGridMin;
uniform vec3 uGridCell;
uniform ivec3 uGridDims;
uniform ivec3 uBins;
uniform int uBinVoxels;
#ifdef SL_LIT_REACH
// After common.glsl (litReaches): the volume holds V = S / A and only spot lights shine; a voxel
// no cone reaches within uReach (its half-diagonal) is marked with weight −1 and left 0 by the
// normalisation, not counted as uncovered (the CPU gather's LitReach).
uniform float uReach;
#endif
#ifdef SL_OCCLUSION
uniform float uDensityVoxel;  // smallest density voxel edge (world units)
#endif
#ifdef SL_BOUNDED
uniform vec2 uTaylorBounds;  // TaylorBounds (lo, hi): each Taylor estimate is clamped to it
#endif
#ifdef SL_LAMP_BOUNDS
// After common.glsl (its lamp functions): the clamp's hi tightened for this frame on the GPU, as
// shading/transport.h lampBounds does on the host: hi = min(hi, 1 / min_l m_l(box diagonal)),
// its ln for ln V (SL_LOG_SPACE), from the lights and the density at each lamp (min_l m_l from
// the lamp model's pass, lights[0].lamp.y: lamp_k.comp.glsl), so that the host never reads the
// density around the lamps inside a frame.
float lampTaylorHi(float hi) {
  float m = uLightCount > 0 ? lights[0].lamp.y : 1.0;
#ifdef SL_LOG_SPACE
  return min(hi, log(1.0 / m));
#else
  return min(hi, 1.0 / m);
#endif
}
#endif

void main() {
  ivec3 v = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(v, uGridDims))) return;
  // The rasterised splat's voxel centre: (min.xy + gl_FragCoord.xy·cell.xy, the slice's z).
  precise vec3 x = vec3(uGridMin.xy + (vec2(v.xy) + 0.5) * uGridCell.xy,
                        uGridMin.z + (float(v.z) + 0.5) * uGridCell.z);
#ifdef SL_LIT_REACH
  if (!litReaches(x, uReach)) {
    imageStore(uSums, v, vec4(0.0, 0.0, 0.0, -1.0));
    return;
  }
#endif
  ivec3 b = v / uBinVoxels;
  int bin = (b.z * uBins.y + b.y) * uBins.x + b.x;
  vec4 sum = vec4(0.0);
#ifdef SL_BOUNDED
  float hi = uTaylorBounds.y;
#ifdef SL_LAMP_BOUNDS
  hi = lampTaylorHi(hi);
#endif
#endif
  for (uint k = binOffsets[bin]; k < binOffsets[bin + 1]; ++k) {
    uint j = binItems[k];
    vec4 positionRadius = points[j];
    precise vec3 d = x - positionRadius.xyz;
    float R = positionRadius.w;
    // Inside the valid sphere by the CPU's test (cpu/gather_rows_impl.h: d² < R², d² summed
    // in its order, `precise`: no fused multiply-add): decided without a square root, so that
    // a GPU's approximate sqrt (a few ulps) cannot move a voxel centre on the sphere in or out
    // (W is about 1 there, not 0: with length(d) < R and a sqrt simulated 4 ulps off, the
    // shipped chimney's `adaptive` image moved by 2.4e-4 relative L2).
    precise float d2 = d.x * d.x + (d.y * d.y + d.z * d.z);
    precise float R2 = R * R;
    if (!(d2 < R2)) continue;
    float dist = sqrt(d2);
    float W = R / max(dist, SL_SINGULAR_EPS * R);
#ifdef SL_OCCLUSION
    // Its steps as the CPU counts them: the length in its arithmetic (cpuLength, glm::length).
    vec3 p = positionRadius.xyz;
    float len = cpuLength(d);
    int steps = stepCount(len, uDensityVoxel);
    float tau = 0.0;
    for (int m = 0; m < steps; ++m)
      tau += densityAtIndex((p + d * ((float(m) + 0.5) / float(steps))) * uDensityScale +
                            uDensityOffset);
    W *= exp(-uSigmaT * tau * (len / float(steps)));
#endif
    GatherRecord s = records[j];
    vec3 taylor = s.S.rgb + d.x * s.dS[0].rgb + d.y * s.dS[1].rgb + d.z * s.dS[2].rgb;
#ifdef SL_BOUNDED
    taylor = clamp(taylor, vec3(uTaylorBounds.x), vec3(hi));
#endif
    sum += vec4(W * taylor, W);
  }
  imageStore(uSums, v, sum);
}
