#pragma once
/// Phase functions, normalised to 1 over the sphere (pbrt's convention).

#include "core/math.h"

namespace scatterlab {

struct Phase {
  enum class Type { Isotropic, HenyeyGreenstein };
  Type type = Type::Isotropic;
  float g = 0.0f;  ///< HG asymmetry in (-1, 1); g > 0 scatters forward.

  /// Phase value for light travelling along `lightDir` (from the light towards the point) that
  /// leaves along `outDir` (from the point towards the viewer); both unit length.
  /// cos = dot(lightDir, outDir) = 1 means no deflection, where forward scattering peaks.
  float eval(const Vec3& lightDir, const Vec3& outDir) const {
    return evalCos(glm::dot(lightDir, outDir));
  }

  /// Same, from the cosine of the deflection angle.
  float evalCos(float cosTheta) const {
    if (type == Type::Isotropic) return kInvFourPi;
    const float denom = 1.0f + g * g - 2.0f * g * cosTheta;
    return kInvFourPi * (1.0f - g * g) / (denom * std::sqrt(denom));
  }
};

}  // namespace scatterlab
