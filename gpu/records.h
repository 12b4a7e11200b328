#pragma once
/// The std430 records of the shaders' storage buffers, mirrored in C++. Each struct matches one
/// GLSL struct (or array element) byte for byte: the std430 offsets are written next to each
/// and asserted below, so a buffer is uploaded or read back as a vector of these structs and no
/// code counts floats. A vec3 occupies a 16-byte slot in std430 arrays and structs, hence the
/// explicit padding. No context needed.

#include <cstddef>
#include <cstdint>

#include "core/density_model.h"
#include "core/light.h"
#include "core/stages.h"

namespace scatterlab::gpu {

/// A vec3 in a vec4 slot (std430 aligns vec3 to 16 bytes); `w` is unused.
struct PaddedVec3 {
  Vec3 v{0.0f};    // offset 0
  float w = 0.0f;  // offset 12
};
static_assert(sizeof(PaddedVec3) == 16);

/// common.glsl `GpuLight` (lights[] at BINDING_LIGHTS). std430: positionType 0,
/// directionCosInner 16, intensityCosOuter 32, lamp 48; stride 64.
struct GpuLight {
  Vec3 position{0.0f};   // positionType.xyz
  float type = 0.0f;     // positionType.w: Light::Type order (0 point, 1 spot, 2 directional)
  Vec3 direction{0.0f};  // directionCosInner.xyz
  float cosInner = 0.0f;
  Vec3 intensity{0.0f};  // intensityCosOuter.rgb
  float cosOuter = 0.0f;
  /// lamp.x: k_l of the lamp model (LampModel::k), written on the device by the lamp model's
  /// pass (gpu::deviceLights; 0 until then, and for a light the model leaves at 1).
  float lampK = 0.0f;
  /// lamp.y of lights[0]: min_l m_l at the box's diagonal (1 / LampModel::vBound), by the same
  /// pass; 1 (no lamp inside the box) until then. Unused in the other lights.
  float lampMin = 1.0f;
  /// lamp.z: glowScale (kGlowRatio / glowAngle), the glow's substep scale of the factored march
  /// (core/stages.h); 0 for a directional light.
  float glow = 0.0f;
  float unused = 0.0f;
};
static_assert(sizeof(GpuLight) == 64);
static_assert(offsetof(GpuLight, position) == 0 && offsetof(GpuLight, type) == 12);
static_assert(offsetof(GpuLight, direction) == 16 && offsetof(GpuLight, cosInner) == 28);
static_assert(offsetof(GpuLight, intensity) == 32 && offsetof(GpuLight, cosOuter) == 44);
static_assert(offsetof(GpuLight, lampK) == 48 && offsetof(GpuLight, lampMin) == 52);
static_assert(offsetof(GpuLight, glow) == 56);

inline GpuLight packLight(const Light& l) {
  const float type = l.type == Light::Type::Point  ? 0.0f
                     : l.type == Light::Type::Spot ? 1.0f
                                                   : 2.0f;
  return {l.position, type, l.direction, l.cosInner,  l.intensity,
          l.cosOuter, 0.0f, 1.0f,        glowScale(l)};
}

/// A sample's position and valid radius: `vec4` (xyz, w = radius) of samples[] at
/// BINDING_SAMPLES and nextSamples[] at BINDING_NEXT_SAMPLES. std430: xyz 0, w 12; stride 16.
/// The volume tracer ignores w.
struct GpuSamplePoint {
  Vec3 position{0.0f};
  float radius = 0.0f;
};
static_assert(sizeof(GpuSamplePoint) == 16);
static_assert(offsetof(GpuSamplePoint, position) == 0 && offsetof(GpuSamplePoint, radius) == 12);

/// common.glsl `RadianceRecord` (results[] at BINDING_RADIANCE): S and the three rows of ∇S,
/// 16 floats. std430: S 0, dS[0] 16, dS[1] 32, dS[2] 48 (array stride 16); stride 64.
struct GpuRadianceRecord {
  PaddedVec3 S;
  PaddedVec3 dS[3];  ///< dS[a]: RGB derivative along world axis a
};
static_assert(sizeof(GpuRadianceRecord) == 64);
static_assert(offsetof(GpuRadianceRecord, S) == 0 && offsetof(GpuRadianceRecord, dS) == 16);

inline GpuRadianceRecord packRadiance(const RadianceSample& s) {
  return {{s.S}, {{s.dS[0]}, {s.dS[1]}, {s.dS[2]}}};
}

/// Copies S and ∇S of `r` into `s` (its position, radius and level are left alone).
inline void unpackRadiance(const GpuRadianceRecord& r, RadianceSample& s) {
  s.S = r.S.v;
  for (int a = 0; a < 3; ++a) s.dS[a] = r.dS[a].v;
}

/// radiance_splat.vert.glsl `SplatSample` (samples[] at BINDING_SPLAT_SAMPLES). std430:
/// positionRadius 0, radiance 16 (a RadianceRecord: S 16, dS 32..79); stride 80.
struct GpuSplatSample {
  GpuSamplePoint point;
  GpuRadianceRecord radiance;
};
static_assert(sizeof(GpuSplatSample) == 80);
static_assert(offsetof(GpuSplatSample, point) == 0 && offsetof(GpuSplatSample, radiance) == 16);

/// density_splat.vert.glsl `Blob` (blobs[] at BINDING_BLOBS). std430: centerRadius 0,
/// weight 16 (x used); stride 32.
struct GpuBlob {
  Vec3 center{0.0f};
  float radius = 0.0f;
  float weight = 0.0f;
  float unused[3] = {0.0f, 0.0f, 0.0f};
};
static_assert(sizeof(GpuBlob) == 32);
static_assert(offsetof(GpuBlob, center) == 0 && offsetof(GpuBlob, radius) == 12);
static_assert(offsetof(GpuBlob, weight) == 16);

inline GpuBlob packBlob(const GaussianBlob& b) {
  return {b.center, b.radius, b.weight};
}

/// view_march.comp.glsl `MarchCounts` (at BINDING_COUNTERS): steps looked up and steps jumped
/// over (empty-space skipping), each a 64-bit count as two 32-bit words (low, high); size 16.
struct GpuMarchCounters {
  std::uint32_t looked[2] = {0, 0};
  std::uint32_t skipped[2] = {0, 0};
  static long long join(const std::uint32_t w[2]) {
    return (long long)w[0] | ((long long)w[1] << 32);
  }
};
static_assert(sizeof(GpuMarchCounters) == 16);

/// per_voxel.comp.glsl `Counters` (at BINDING_COUNTERS). std430: traced 0, skipped 4; size 8.
struct GpuPerVoxelCounters {
  std::uint32_t traced = 0;
  std::uint32_t skipped = 0;
};
static_assert(sizeof(GpuPerVoxelCounters) == 8);
static_assert(offsetof(GpuPerVoxelCounters, traced) == 0 &&
              offsetof(GpuPerVoxelCounters, skipped) == 4);

}  // namespace scatterlab::gpu
