// Dynamic sampling (paper Sec. 5), one invocation per sample of the current level: S and ∇S
// (as volume_tracer.comp.glsl), the traced S and the density at the probes x_j + R_j·d_i,
// τ to the viewer, the local shading error E_j of Eq. 5 and, on level 0, the sample's
// contribution R³·mean|S|·D·τ (the scale of a relative ε). The level's sample count is read
// from the GPU (counts[uLevel], written by the count pass of dynamic_level.comp.glsl; the
// dispatch is indirect); the threshold and the split decisions are left to the next passes.
// Mirrors sampling/dynamic_sampling.cpp (localShadingError, sampleContribution,
// viewTransmittance) operation for operation.
layout(local_size_x = 64) in;

layout(std430, binding = BINDING_SAMPLES) readonly buffer Samples { vec4 samples[]; };  // xyz, valid radius
layout(std430, binding = BINDING_ANCESTORS) readonly buffer Ancestors { int ancestors[]; };
layout(std430, binding = BINDING_ROOT_TAU) buffer RootTau { float rootTau[]; };  // τ of every level-0 sample
layout(std430, binding = BINDING_RADIANCE) writeonly buffer Results { RadianceRecord results[]; };
// E_j at [j]; on level 0 also the contribution at [count + j]
layout(std430, binding = BINDING_ERRORS) writeonly buffer Errors { float errors[]; };
layout(std430, binding = BINDING_LEVEL_COUNTS) readonly buffer LevelCounts { uint counts[]; };

uniform uint uLevel;            // k: the level's sample count is counts[k]
uniform float uDelta2;
uniform int uProbes;            // 6, 14, 26 or 40
uniform vec3 uProbeDirs[40];    // probeOffsets() of the CPU
uniform int uTauMode;           // 0: level 0 (trace τ, store it in rootTau), 1: ancestor's, 2: own
uniform float uTauDelta1;       // step of the τ trace
uniform int uVisibleTau;        // 1: τ = max(τ, τ at the six axis probes) (tau "visible")
uniform int uFinal;             // 1: finest level, S and ∇S only; 2: S only (∇S = 0)
uniform vec3 uDensityInvCell;   // DensityGrid::sample: u = (p − min)·invCell − 0.5
#ifdef SL_BOUNDED
uniform vec2 uTaylorBounds;     // TaylorBounds (lo, hi): the Taylor estimate is clamped to it
#endif

// DensityGrid::sample: 0 outside the (closed) box.
float densityAt(vec3 p) {
  if (any(lessThan(p, uBoxMin)) || any(greaterThan(p, uBoxMax))) return 0.0;
  precise vec3 u = (p - uBoxMin) * uDensityInvCell - 0.5;
  return densityAtIndex(u);
}

float viewTransmittance(vec3 x) { return exp(-uSigmaT * opticalDepth(x, uEye, uTauDelta1)); }

void main() {
  uint j = gl_GlobalInvocationID.x;
  uint count = counts[uLevel];
  if (j >= count) return;
  vec4 pr = samples[j];
  vec3 x = pr.xyz;
  float R = pr.w;
  vec3 S = sourceTowardsEye(x);
  vec3 dS[3];
  for (int a = 0; a < 3; ++a) {
    vec3 e = vec3(0.0);
    e[a] = uDelta2;
    // uFinal 2: the per-voxel fallback's voxels, S only (the CPU's gradients = false).
    dS[a] = uFinal == 2 ? vec3(0.0)
                        : (sourceTowardsEye(x + e) - sourceTowardsEye(x - e)) / (2.0 * uDelta2);
  }
  results[j].S = vec4(S, 0.0);
  for (int a = 0; a < 3; ++a) results[j].dS[a] = vec4(dS[a], 0.0);
  if (uFinal != 0) {
    errors[j] = 0.0;
    return;
  }
  float tau;
  if (uTauMode == 0) {
    tau = viewTransmittance(x);
    rootTau[j] = tau;
  } else if (uTauMode == 1) {
    tau = rootTau[ancestors[j]];
  } else {
    tau = viewTransmittance(x);
  }
  if (uVisibleTau != 0) {
    // tau "visible": the most visible of the sample and its six axis probes (the CPU's
    // probePoints order; rootTau keeps the centre's τ).
    for (int i = 0; i < 6; ++i) {
      precise vec3 p = x + R * uProbeDirs[i];
      tau = max(tau, viewTransmittance(p));
    }
  }
  precise float sum = 0.0;
  for (int i = 0; i < uProbes; ++i) {
    precise vec3 p = x + R * uProbeDirs[i];
    vec3 Sp = sourceTowardsEye(p);
    float D = densityAt(p);
    precise vec3 d = p - x;
    precise vec3 taylor = S + d.x * dS[0] + d.y * dS[1] + d.z * dS[2];
#ifdef SL_BOUNDED
    taylor = clamp(taylor, vec3(uTaylorBounds.x), vec3(uTaylorBounds.y));
#endif
#ifdef SL_LOG_SPACE
    // ln V held: compared on V, what the image sees (localShadingError's ErrorSpace::log).
    precise vec3 diff = abs(exp(taylor) - exp(Sp));
#else
    precise vec3 diff = abs(taylor - Sp);
#endif
    sum += (diff.x + diff.y + diff.z) / 3.0 * D;
  }
  precise float E = R * R * R * sum / float(uProbes) * tau;
  errors[j] = E;
  if (uTauMode == 0) {
#ifdef SL_LOG_SPACE
    precise vec3 a = exp(S);
#else
    precise vec3 a = abs(S);
#endif
    precise float c = R * R * R * ((a.x + a.y + a.z) / 3.0) * densityAt(x) * tau;
    errors[count + j] = c;
  }
}
