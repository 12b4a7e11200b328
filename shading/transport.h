#pragma once
/// Transport physics shared by every backend and stage (volume tracing, paper Sec. 4, Eq. 1):
/// transmittance along straight segments through the density volume, and the source radiance S(x,
/// ω) = Σ_l f(ω_l → ω)·E_l(x) of DESIGN.md §2. Header-only templates so the inner loops inline; no
/// virtual calls per step.

#include <array>
#include <vector>

#include "core/grid.h"
#include "core/light.h"
#include "core/max_density_grid.h"
#include "core/phase.h"
#include "core/scene.h"
#include "core/stages.h"

namespace scatterlab {

/// ∫ D along the segment a→b, restricted to `box`, by the midpoint rule with steps of at most
/// `step` (the paper's Δ1). `field(p)` returns D at a world point inside the box.
template <class Field>
float opticalDepth(const Field& field, const Box& box, const Vec3& a, const Vec3& b, float step) {
  const Vec3 d = b - a;
  const float len = glm::length(d);
  if (len <= 0.0f) return 0.0f;
  const Ray r{a, d / len};
  float t0, t1;
  if (!box.intersect(r, t0, t1, 0.0f, len) || t1 <= t0) return 0.0f;
  const int n = stepCount(t1 - t0, step);
  const float dt = (t1 - t0) / float(n);
  float sum = 0.0f;
  for (int i = 0; i < n; ++i) sum += field(r.at(t0 + (float(i) + 0.5f) * dt));
  return sum * dt;
}

/// The midpoint-rule steps of the segment a→b clipped to grid g's box, in g's index space: step
/// i looks up u0 + i·du, n steps of dt world units (at most `step`); n = 0 when the segment is
/// empty or misses the box. With `clipInside` false the clip is skipped when both ends lie in
/// the box ([0, len], what the clip gives unless b is on the boundary and the exit rounds an
/// ulp short of len).
struct IndexSteps {
  Vec3 u0{0.0f}, du{0.0f};
  int n = 0;
  float dt = 0.0f;
};

inline IndexSteps indexSteps(const DensityGrid& g, const Vec3& a, const Vec3& b, float step,
                             bool clipInside = true) {
  IndexSteps out;
  const Vec3 d = b - a;
  const float len = glm::length(d);
  if (len <= 0.0f) return out;
  const Ray r{a, d / len};
  float t0 = 0.0f, t1 = len;
  const Box& box = g.bounds();
  if ((clipInside || !(box.contains(a) && box.contains(b))) &&
      (!box.intersect(r, t0, t1, 0.0f, len) || t1 <= t0))
    return out;
  out.n = stepCount(t1 - t0, step);
  out.dt = (t1 - t0) / float(out.n);
  const Vec3 s = g.indexScale();
  out.u0 = r.at(t0 + 0.5f * out.dt) * s + g.indexOffset();
  out.du = r.dir * out.dt * s;
  return out;
}

/// opticalDepth(g, a, b, step) that stops once the sum passes `maxDepth` (checked every
/// eight steps): the same sum until then, so the same result where the depth stays below it.
inline float opticalDepth(const DensityGrid& g, const Vec3& a, const Vec3& b, float step,
                          float maxDepth) {
  const IndexSteps st = indexSteps(g, a, b, step);
  if (st.n == 0) return 0.0f;
  const int n = st.n;
  const float dt = st.dt;
  const Vec3 u0 = st.u0, du = st.du;
  const float sumMax = maxDepth / dt;
  float sum = 0.0f;
  for (int i = 0; i < n && sum <= sumMax;)
    for (const int e = std::min(n, i + 8); i < e; ++i) sum += g.sampleIndex(u0 + float(i) * du);
  return sum * dt;
}

/// Fast path of opticalDepth for a DensityGrid covering `box`: marches in index space (the
/// stopping overload never stops: the same sum in the same order).
inline float opticalDepth(const DensityGrid& g, const Vec3& a, const Vec3& b, float step) {
  return opticalDepth(g, a, b, step, std::numeric_limits<float>::infinity());
}

/// The density integral ∫D at which a shadow ray stops: kShadowDepthCutoff (core/stages.h) / σt
/// (never for σt = 0).
inline float shadowDepthCutoff(float sigmaT) {
  return sigmaT > 0.0f ? kShadowDepthCutoff / sigmaT : kInfinity;
}

/// opticalDepth(g, a, b, step) skipping the steps in blocks of `skip` (built from g) whose
/// maximum is zero: the same steps are summed in the same order, so the result is the same,
/// unless the sum passes `maxDepth`, checked after each block: then it stops there (a depth
/// beyond maxDepth, smaller than the whole segment's).
inline float opticalDepth(const DensityGrid& g, const MaxDensityGrid& skip, const Vec3& a,
                          const Vec3& b, float step, float maxDepth = kInfinity) {
  const IndexSteps st = indexSteps(g, a, b, step);
  if (st.n == 0) return 0.0f;
  const int n = st.n;
  const float dt = st.dt;
  const Vec3 u0 = st.u0, du = st.du;
  MaxDensityGrid::Walk walk(skip, u0, du, n);
  const float sumMax = maxDepth / dt;
  float sum = 0.0f;
  for (int i = 0; i < n && sum <= sumMax;) {
    const MaxDensityGrid::Span sp = walk.span(i);
    if (!sp.empty)
      for (; i < sp.end; ++i) sum += g.sampleIndex(u0 + float(i) * du);
    i = sp.end;
  }
  return sum * dt;
}

/// The unit direction from x to the viewer at `eye` (+Z when x is the eye): the toViewer every
/// S(x, ω) and A(x, ω) of the samples, probes and voxels is evaluated with.
inline Vec3 towardsEye(const Vec3& eye, const Vec3& x) {
  const Vec3 v = eye - x;
  const float len = glm::length(v);
  return len > 0.0f ? v / len : Vec3(0, 0, 1);
}

/// The far end of the segment from x towards a light: the light itself, or for directional
/// lights the point where the ray leaves the box (or x when it is outside).
inline Vec3 lightSegmentEnd(const Light& l, const Light::Incident& inc, const Box& box,
                            const Vec3& x) {
  if (l.type != Light::Type::Directional) return x + inc.toLight * inc.distance;
  float t0, t1;
  if (!box.intersect(Ray{x, inc.toLight}, t0, t1)) return x;
  return x + inc.toLight * t1;
}

/// A replacement for the shadow rays' opticalDepth(density, a, b, step, maxDepth) (the one with a
/// cutoff): fn(ctx, a, b, step, maxDepth). cpu/shadow_rays.h provides the SIMD one `exact` uses.
struct ShadowDepthFn {
  float (*fn)(const void* ctx, const Vec3& a, const Vec3& b, float step, float maxDepth) = nullptr;
  const void* ctx = nullptr;
};

/// Evaluates the source radiance S(x, ω) for the scene's lights through a density volume.
/// S excludes σs and D: the in-scattered radiance per unit length is σs·D(x)·S(x, ω).
class SourceRadiance {
 public:
  /// `delta1`: volume tracing step (world units). `skip` (optional, built from `density`):
  /// the shadow rays skip its empty blocks (same sums). With `skip` or `cutoff` they stop at
  /// an optical depth of kShadowDepthCutoff / σt (transmittance below 1.4e-11). References
  /// must outlive this object. `shadow` (optional): traces the shadow rays instead, with the
  /// cutoff (and without `skip`).
  SourceRadiance(const Scene& scene, const DensityGrid& density, float delta1,
                 const MaxDensityGrid* skip = nullptr, bool cutoff = false,
                 ShadowDepthFn shadow = {})
      : lights_(scene.lights),
        phase_(scene.medium.phase),
        sigmaT_(scene.medium.sigmaT),
        density_(density),
        delta1_(delta1),
        objects_(scene.objects.get()),
        skip_(skip),
        shadow_(shadow),
        cutoff_(cutoff || skip || shadow.fn),
        depthCutoff_(shadowDepthCutoff(sigmaT_)) {
    for (const Light& l : lights_) glowScale_.push_back(glowScale(l));
  }

  /// S at x for light leaving towards the viewer along unit `toViewer`.
  Vec3 operator()(const Vec3& x, const Vec3& toViewer) const {
    Vec3 s(0.0f);
    for (const Light& l : lights_) s += term(l, x, toViewer);
    return s;
  }

  /// S over the view-march step of length dt centred at r.at(t), seen along −r.dir (what
  /// `exact` marches): per light as operator(), or where the midpoint lies within a point or
  /// spot light's glow (core/stages.h, glowSubsteps) its term (shadow ray included) averaged
  /// over the substeps' midpoints — the factored march's quadrature of A
  /// (LightFactor::overStep), so that the reference resolves a glow as the methods do.
  Vec3 overStep(const Ray& r, float t, float dt) const {
    const Vec3 x = r.at(t), toViewer = -r.dir;
    Vec3 s(0.0f);
    for (std::size_t i = 0; i < lights_.size(); ++i) {
      const Light& l = lights_[i];
      const int n = glow_ ? lightGlowSubsteps(glowScale_[i], l.position, x, r.dir, dt) : 1;
      if (n == 1) {
        s += term(l, x, toViewer);
        continue;
      }
      Vec3 a(0.0f);
      for (int m = 0; m < n; ++m) a += term(l, r.at(glowSubstepT(t, dt, m, n)), toViewer);
      s += a / float(n);
    }
    return s;
  }

 private:
  /// Light l's term of S at x (operator()'s): its irradiance, phase and V_l·T.
  Vec3 term(const Light& l, const Vec3& x, const Vec3& toViewer) const {
    Light::Incident inc;
    if (!l.incident(x, inc)) return Vec3(0.0f);
    return inc.irradiance * (phase_.eval(-inc.toLight, toViewer) * transmittance(l, inc, x));
  }

  /// V_l·T from x towards light l (inc: its direction and distance from x).
  float transmittance(const Light& l, const Light::Incident& inc, const Vec3& x) const {
    if (objects_ && objects_->occluded(x, inc.toLight, 0.0f, inc.distance)) return 0.0f;
    const Vec3 end = lightSegmentEnd(l, inc, density_.bounds(), x);
    const float tau = shadow_.fn ? shadow_.fn(shadow_.ctx, x, end, delta1_, depthCutoff_)
                      : skip_    ? opticalDepth(density_, *skip_, x, end, delta1_, depthCutoff_)
                      : cutoff_  ? opticalDepth(density_, x, end, delta1_, depthCutoff_)
                                 : opticalDepth(density_, x, end, delta1_);
    return std::exp(-sigmaT_ * tau);
  }

  const std::vector<Light>& lights_;
  Phase phase_;
  float sigmaT_;
  const DensityGrid& density_;
  float delta1_;
  const SceneObjects* objects_;   ///< V_l: null when the scene has no objects
  const MaxDensityGrid* skip_;    ///< empty-space skipping of the shadow rays, or null
  ShadowDepthFn shadow_;          ///< the shadow rays' tracer, when given
  bool cutoff_;                   ///< shadow rays stop at depthCutoff_ (always with skip_)
  float depthCutoff_;             ///< τ at which a shadow ray stops
  bool glow_ = true;              ///< overStep's substeps (render.glow)
  std::vector<float> glowScale_;  ///< glowScale of each light

 public:
  /// render.glow false: overStep takes S at the step's midpoint only.
  void setGlow(bool glow) { glow_ = glow; }
};

/// The radiance leaving a Lambertian surface point towards any direction (DESIGN.md §2):
/// L_p = albedo/π · Σ_l E_l(p)·max(0, n·ω_l)·V_l(p)·T(p, l), with V_l through the scene's
/// objects (shadow rays leave p offset by the objects' epsilon along n) and T traced through
/// the density volume with step delta1. Every method shades surfaces with this, per pixel.
class SurfaceRadiance {
 public:
  /// References must outlive this object.
  SurfaceRadiance(const Scene& scene, const DensityGrid& density, float delta1)
      : lights_(scene.lights),
        sigmaT_(scene.medium.sigmaT),
        density_(density),
        delta1_(delta1),
        objects_(scene.objects.get()) {}

  Vec3 operator()(const SurfaceHit& h) const {
    if (h.albedo == Vec3(0.0f)) return Vec3(0.0f);
    const Vec3 p = h.position + h.normal * (objects_ ? objects_->epsilon() : 0.0f);
    Vec3 e(0.0f);
    for (const Light& l : lights_) {
      Light::Incident inc;
      if (!l.incident(p, inc)) continue;
      // The light must be in front of the face itself; the cosine is the shading normal's.
      const float cosine = glm::dot(h.shading, inc.toLight);
      if (cosine <= 0.0f || glm::dot(h.normal, inc.toLight) <= 0.0f) continue;
      if (objects_ && objects_->occluded(p, inc.toLight, 0.0f, inc.distance)) continue;
      const float tau =
          opticalDepth(density_, p, lightSegmentEnd(l, inc, density_.bounds(), p), delta1_);
      e += inc.irradiance * (cosine * std::exp(-sigmaT_ * tau));
    }
    return h.albedo * e * (1.0f / kPi);
  }

 private:
  const std::vector<Light>& lights_;
  float sigmaT_;
  const DensityGrid& density_;
  float delta1_;
  const SceneObjects* objects_;
};

/// The near-lamp transmittance model (docs/fidelity.md §8): for point or spot light l inside the
/// medium, m_l(x) = exp(−κ·q / (q + κ)), q = k_l·‖x − s_l‖, k_l = σt·D(s_l) the extinction at
/// the light, κ = kLampDepth. Next to the lamp m_l is the transmittance e^(−k_l·d) of a
/// homogeneous medium (the cusp of T_l at the lamp), far away the constant e^(−κ); smooth in
/// between. Directional lights and lights outside the medium's box (or where D = 0): m = 1.
/// Default-constructed: off (every m = 1, nothing computed).
class LampModel {
 public:
  LampModel() = default;
  LampModel(const Scene& scene, const DensityGrid& density)
      : LampModel(scene, density.bounds(), [&](const Vec3& p) { return density.sample(p); }) {}
  /// With the density at a point of `box` from `densityAt` (DensityGrid::sample's value; the
  /// GPU reads the eight voxels around each light instead of the whole volume).
  template <class DensityAt>
  LampModel(const Scene& scene, const Box& box, DensityAt densityAt) : on_(true) {
    k_.reserve(scene.lights.size());
    for (const Light& l : scene.lights) {
      const bool inside = l.type != Light::Type::Directional && box.contains(l.position);
      k_.push_back(inside ? scene.medium.sigmaT * densityAt(l.position) : 0.0f);
    }
  }
  bool on() const { return on_; }
  /// k_l = σt·D(s_l) of light i: m_l = exp(−kLampDepth·q / (q + kLampDepth)), q = k_l·distance;
  /// 0 where m_l = 1 (off, directional lights, lights outside the box).
  float k(std::size_t i) const { return on_ ? k_[i] : 0.0f; }
  /// m_l at `distance` from light i.
  float operator()(std::size_t i, float distance) const {
    const float k = k_[i];
    if (!(k > 0.0f)) return 1.0f;
    const float q = k * distance;
    return lampTransmittance(q);
  }
  /// An upper bound of V = S / A with the model: 1 / min m_l over the box of diagonal `diag`
  /// (V = Σ w·T / Σ w·m <= max_l T_l / m_l <= max_l 1 / m_l(diag)); 1 without lamps inside.
  float vBound(float diag) const {
    float m = 1.0f;
    for (std::size_t i = 0; i < k_.size(); ++i) m = std::min(m, (*this)(i, diag));
    return 1.0f / m;
  }

 private:
  bool on_ = false;
  std::vector<float> k_;  ///< k_l = σt·D(s_l), 0 where the model is 1
};

/// `b` (V's bounds with the model, taylorBounds()) tightened for one frame: hi = LampModel's
/// vBound for the scene's lights and density, so the Taylor clamp is V <= 1 again where no lamp
/// sits in the medium. Log bounds (lo < 0) get ln of it.
inline TaylorBounds lampBounds(TaylorBounds b, const LampModel& model, const Box& box) {
  const float v = model.vBound(glm::length(box.extent()));
  if (b.lo < 0.0f)
    b.hi = std::min(b.hi, std::log(v));
  else
    b.hi = std::min(b.hi, v);
  return b;
}
inline TaylorBounds lampBounds(TaylorBounds b, const Scene& scene, const DensityGrid& density) {
  return lampBounds(b, LampModel(scene, density), density.bounds());
}

/// A's far field (render.far_field; docs/gpu.md, "A's far field on a grid"): each point light's
/// term of A split by w_l(x) = smoothstep(R, 2R, |p_l − x|) into a near part (1 − w_l)·A_l, which
/// the factored march evaluates at every step as before, and a far part w_l·A_l, summed over the
/// lights at the vertices of a grid over the medium's box (one per voxel corner) and interpolated
/// trilinearly between them: near no lamp a step looks the grid up instead of evaluating every
/// light. Spot and directional lights stay exact (w = 0). Only for the isotropic phase function,
/// where A does not depend on the direction to the camera (with Henyey–Greenstein it does, and a
/// grid interpolates it badly where it turns fast). The GPU's farWeight and farLookup
/// (gpu/shaders/common.glsl) are the same arithmetic.
struct FarField {
  float radius = 0.0f;        ///< R in world units; 0: off
  IVec3 dims{0};              ///< vertices per axis (the voxels + 1)
  Vec3 lo{0.0f}, cell{1.0f};  ///< vertex (i, j, k) at lo + (i, j, k) · cell
  std::vector<Vec3> a;        ///< Σ_l w_l·A_l at each vertex, x fastest

  bool on() const { return radius > 0.0f; }
  /// w_l at x: 0 within R of a point light, 1 beyond 2R (smoothly between); 0 for other lights.
  float weight(const Light& l, const Vec3& x) const {
    if (l.type != Light::Type::Point) return 0.0f;
    const float u = std::clamp((glm::length(l.position - x) - radius) / radius, 0.0f, 1.0f);
    return u * u * (3.0f - 2.0f * u);
  }
  /// The far part at x, trilinear between the grid's vertices (x clamped into the box).
  Vec3 lookup(const Vec3& x) const {
    const Vec3 u = glm::clamp((x - lo) / cell, Vec3(0.0f), Vec3(dims - IVec3(1)));
    const IVec3 b = glm::min(IVec3(glm::floor(u)), dims - IVec3(2));
    const Vec3 t = u - Vec3(b);
    const auto at = [&](int i, int j, int k) {
      return a[(std::size_t(k) * std::size_t(dims.y) + std::size_t(j)) * std::size_t(dims.x) +
               std::size_t(i)];
    };
    const Vec3 c00 = glm::mix(at(b.x, b.y, b.z), at(b.x + 1, b.y, b.z), t.x);
    const Vec3 c10 = glm::mix(at(b.x, b.y + 1, b.z), at(b.x + 1, b.y + 1, b.z), t.x);
    const Vec3 c01 = glm::mix(at(b.x, b.y, b.z + 1), at(b.x + 1, b.y, b.z + 1), t.x);
    const Vec3 c11 = glm::mix(at(b.x, b.y + 1, b.z + 1), at(b.x + 1, b.y + 1, b.z + 1), t.x);
    return glm::mix(glm::mix(c00, c10, t.y), glm::mix(c01, c11, t.y), t.z);
  }
};

/// The singular-light factorization (docs/fidelity.md): S(x, ω) = A(x, ω) ⊙ V(x, ω), per RGB
/// channel, with A = Σ_l f(ω_l → ω)·E⁰_l(x) the analytic, unshadowed source radiance (E⁰ =
/// I·cone/d² for point and spot lights, the sun's irradiance for directional ones) and
/// V = S / A the light-weighted transmittance, in [0, 1]. A carries the 1/d² singularity, the
/// spot cone's edge and the phase function exactly; V is as smooth as the transmittance, so
/// V is what the samples hold and the volume interpolates, and the integrator multiplies A
/// back at each step.
class LightFactor {
 public:
  /// References must outlive this object. `lamp` (on: PipelineSettings::lampModel): each
  /// light's term times its near-lamp model m_l.
  /// `glow` (render.glow): overStep averages a light's term over the substeps of its glow.
  explicit LightFactor(const Scene& scene, LampModel lamp = {}, bool glow = true)
      : lights_(scene.lights), phase_(scene.medium.phase), lamp_(std::move(lamp)), glow_(glow) {
    for (const Light& l : lights_) glowScale_.push_back(glowScale(l));
  }

  /// A(x, toViewer): one analytic evaluation per light (no tracing).
  Vec3 operator()(const Vec3& x, const Vec3& toViewer) const {
    Vec3 a(0.0f);
    for (std::size_t i = 0; i < lights_.size(); ++i) a += term(i, x, toViewer);
    return a;
  }

  /// A over the view-march step of length dt centred at r.at(t), seen along −r.dir: per light
  /// its term there, or where the midpoint lies within a point or spot light's glow (core/stages.h,
  /// glowSubsteps) the mean of its term at r.at(t_m) for n substeps' midpoints t_m — the fast
  /// march's factorGroup and the GPU's lightFactorStep alike.
  /// With a far field (setFarField): its lookup plus each light's near part, (1 − w_l) times
  /// the above; the lights beyond 2R are not evaluated.
  Vec3 overStep(const Ray& r, float t, float dt) const {
    const Vec3 x = r.at(t), toViewer = -r.dir;
    Vec3 a = far_ ? far_->lookup(x) : Vec3(0.0f);
    for (std::size_t i = 0; i < lights_.size(); ++i) {
      const float keep = far_ ? 1.0f - far_->weight(lights_[i], x) : 1.0f;
      if (!(keep > 0.0f)) continue;
      const int n = glow_ ? lightGlowSubsteps(glowScale_[i], lights_[i].position, x, r.dir, dt) : 1;
      Vec3 s(0.0f);
      if (n == 1) {
        s = term(i, x, toViewer);
      } else {
        for (int m = 0; m < n; ++m) s += term(i, r.at(glowSubstepT(t, dt, m, n)), toViewer);
        s /= float(n);
      }
      a += far_ ? keep * s : s;
    }
    return a;
  }

  /// overStep's far field (null: every light exact). The grid must outlive this object.
  void setFarField(const FarField* far) { far_ = far && far->on() ? far : nullptr; }

 private:
  /// Light i's term of A at x (operator()'s).
  Vec3 term(std::size_t i, const Vec3& x, const Vec3& toViewer) const {
    Light::Incident inc;
    if (!lights_[i].incident(x, inc)) return Vec3(0.0f);
    const float m = lamp_.on() ? lamp_(i, inc.distance) : 1.0f;
    return inc.irradiance * (phase_.eval(-inc.toLight, toViewer) * m);
  }

  const std::vector<Light>& lights_;
  Phase phase_;
  LampModel lamp_;
  bool glow_;
  std::vector<float> glowScale_;  ///< glowScale of each light
  const FarField* far_ = nullptr;
};

/// Where A of LightFactor can be non-zero. A point or directional light lights every point;
/// a spot light only its outer cone (spotFalloff is 0 at and beyond cos_outer). Where the
/// volume and the samples hold V = S / A, the march multiplies V by A, so a radiance voxel
/// whose trilinear support (the ball of its half-diagonal, `reach`) meets no cone, and a sample
/// whose sphere of validity grown by that reach meets none, cannot change the image: they are
/// neither traced nor gathered (docs/fidelity.md, "Where no cone reaches"). The test is
/// conservative (the cone widened by kLitMargin radians, the ball by kLitGrow: core/stages.h),
/// so CPU and GPU (litReaches in gpu/shaders/common.glsl, the same formula) may differ only where
/// A is 0.
class LitReach {
 public:
  explicit LitReach(const std::vector<Light>& lights) {
    for (const Light& l : lights) {
      if (l.type != Light::Type::Spot) {
        everywhere_ = true;
        return;
      }
      const float angle = std::acos(std::clamp(l.cosOuter, -1.0f, 1.0f)) + kLitMargin;
      spots_.push_back(
          {l.position, l.direction, std::cos(angle), std::sin(angle), angle > 0.5f * kPi});
    }
  }
  /// Every point may be lit (some light is not a spot): nothing is ever skipped.
  bool everywhere() const { return everywhere_; }
  /// The cells of voxelBound: at most 32 per axis (fewer where the grid has fewer voxels).
  static IVec3 boundCells(IVec3 dims) { return glm::clamp(dims, IVec3(1), IVec3(32)); }
  /// An upper bound of the voxels of a `dims` grid over `box` that a cone reaches within their
  /// half-diagonal, counted by the cells of a boundCells(dims) grid (occupiedCells()' voxel →
  /// cell map, core/stages.h), each tested whole with a ball around its voxels; blocks of 4³
  /// cells are tested first and only the cells of blocks a cone reaches are tested again, so a
  /// narrow cone costs a few hundred tests. Host geometry only. `occupied` (per cell, as indexed
  /// by occupiedCells(), how many of its voxel centres hold density: occupiedVoxelsPerCell();
  /// null: all of them): a reached cell counts its occupied voxels. Every voxel of the cells
  /// when everywhere().
  long long voxelBound(const Box& box, IVec3 dims,
                       const std::vector<int>* occupied = nullptr) const {
    const IVec3 c = boundCells(dims);
    const Vec3 cell = box.extent() / Vec3(dims);
    const float reach = glm::length(cell);
    // Per axis, the first voxel of each cell (and one past the last).
    std::array<std::vector<int>, 3> first;
    for (int a = 0; a < 3; ++a) first[a] = cellStarts(dims[a], c[a]);
    // Cells [k0, k1) per axis: whether a cone reaches the ball around their voxels; their
    // voxels in `count`.
    const auto reached = [&](IVec3 k0, IVec3 k1, long long* count) {
      const IVec3 lo(first[0][std::size_t(k0.x)], first[1][std::size_t(k0.y)],
                     first[2][std::size_t(k0.z)]);
      const IVec3 hi(first[0][std::size_t(k1.x)], first[1][std::size_t(k1.y)],
                     first[2][std::size_t(k1.z)]);
      if (glm::any(glm::lessThanEqual(hi, lo))) return false;
      if (count) *count = (long long)(hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z);
      const Vec3 half = 0.5f * Vec3(hi - lo) * cell;
      return everywhere_ || reaches(box.min + Vec3(lo) * cell + half, glm::length(half) + reach);
    };
    constexpr int kBlock = 4;
    long long n = 0;
    for (int bz = 0; bz < c.z; bz += kBlock)
      for (int by = 0; by < c.y; by += kBlock)
        for (int bx = 0; bx < c.x; bx += kBlock) {
          const IVec3 b0(bx, by, bz), b1 = glm::min(b0 + kBlock, c);
          if (!reached(b0, b1, nullptr)) continue;
          for (int z = b0.z; z < b1.z; ++z)
            for (int y = b0.y; y < b1.y; ++y)
              for (int x = b0.x; x < b1.x; ++x) {
                const int held = occupied ? (*occupied)[std::size_t((z * c.y + y) * c.x + x)] : -1;
                if (held == 0) continue;
                long long voxels = 0;
                if (reached(IVec3(x, y, z), IVec3(x, y, z) + 1, &voxels))
                  n += held < 0 ? voxels : std::min<long long>(voxels, held);
              }
        }
    return n;
  }
  /// Whether some light's A may be non-zero within distance r of c: the ball subtends
  /// β = asin(r / L) seen from the apex (L = |c − apex|), and meets the cone of half-angle θ
  /// (widened by kLitMargin) where the angle α of c to the axis is at most θ + β, i.e.
  /// cos α ≥ cos θ·cos β − sin θ·sin β (always where θ + β ≥ π).
  bool reaches(const Vec3& c, float r) const {
    if (everywhere_) return true;
    r *= kLitGrow;
    for (const Spot& s : spots_) {
      const Vec3 v = c - s.apex;
      const float L = glm::length(v);
      if (L <= r) return true;
      const float sinB = r / L, cosB = std::sqrt(1.0f - sinB * sinB);
      if (s.wide && sinB >= s.sinA) return true;
      if (glm::dot(v, s.axis) >= L * (s.cosA * cosB - s.sinA * sinB)) return true;
    }
    return false;
  }

 private:
  struct Spot {
    Vec3 apex, axis;
    float cosA, sinA;  ///< of the outer half-angle widened by kLitMargin
    bool wide;         ///< that angle is above 90°
  };
  bool everywhere_ = false;
  std::vector<Spot> spots_;
};

/// V(x, ω) = S / A of LightFactor, traced like SourceRadiance. Where A is zero in a channel
/// (outside every spot cone) S is zero too and any V reproduces it; there V is the weighted
/// transmittance with the cones ignored — the continuation of V from inside the cone — so that
/// samples outside a cone do not drag the interpolated V down at its edge.
class FactoredSourceRadiance {
 public:
  /// `delta1`: volume tracing step (world units). `lampModel`: A includes LampModel's m_l,
  /// so V = S / A divides it out (PipelineSettings::lampModel). `shadow` (optional): traces the
  /// shadow rays instead of opticalDepth, stopping at SourceRadiance's cutoff. References must
  /// outlive this object.
  FactoredSourceRadiance(const Scene& scene, const DensityGrid& density, float delta1,
                         bool lampModel = false, ShadowDepthFn shadow = {})
      : lights_(scene.lights),
        phase_(scene.medium.phase),
        sigmaT_(scene.medium.sigmaT),
        density_(density),
        delta1_(delta1),
        objects_(scene.objects.get()),
        lamp_(lampModel ? LampModel(scene, density) : LampModel()),
        shadow_(shadow),
        depthCutoff_(shadowDepthCutoff(sigmaT_)) {
    for (const Light& l : lights_) lit_ = glm::max(lit_, l.intensity);
  }

  Vec3 operator()(const Vec3& x, const Vec3& toViewer) const {
    Vec3 s(0.0f), a(0.0f);
    bool outside = false;  // some light's cone excludes x
    for (std::size_t i = 0; i < lights_.size(); ++i) {
      Term t;
      if (!term(i, x, toViewer, t)) continue;
      if (t.cone <= 0.0f) {
        outside = true;
        continue;
      }
      s += t.w * (t.cone * transmittance(x, t));
      a += t.w * (t.cone * t.m);
    }
    Vec3 v(0.0f), free(-1.0f);
    for (int c = 0; c < 3; ++c) {
      if (a[c] > 0.0f) {
        v[c] = s[c] / a[c];
      } else if (outside && lit_[c] > 0.0f) {
        if (free.x < 0.0f) free = freeV(x, toViewer);
        v[c] = free[c];
      }
    }
    return v;
  }

 private:
  /// One light's analytic weight w = E⁰·f (cone not applied), its cone factor, and the far end
  /// of the segment to trace.
  struct Term {
    Vec3 w, end, toLight;
    float cone = 1.0f;
    float distance = 0.0f;  ///< to the light (infinity: directional), for visibility
    float m = 1.0f;         ///< LampModel's m_l, in A only (1 without the model)
  };
  bool term(std::size_t i, const Vec3& x, const Vec3& toViewer, Term& t) const {
    const Light& l = lights_[i];
    Light::Geometry g;
    if (!l.geometry(x, g)) return false;
    t.cone = g.cone;
    t.toLight = g.toLight;
    t.distance = g.distance;
    Vec3 e0;
    if (l.type == Light::Type::Directional) {
      e0 = l.intensity;
      float t0, t1;
      t.end = density_.bounds().intersect(Ray{x, g.toLight}, t0, t1) ? x + g.toLight * t1 : x;
    } else {
      e0 = l.intensity / g.distance2;
      t.end = l.position;
    }
    t.w = e0 * phase_.eval(-g.toLight, toViewer);
    t.m = lamp_.on() ? lamp_(i, g.distance) : 1.0f;
    return true;
  }
  /// V_l·T towards the light of `t` (objects block it entirely).
  float transmittance(const Vec3& x, const Term& t) const {
    if (objects_ && objects_->occluded(x, t.toLight, 0.0f, t.distance)) return 0.0f;
    const float tau = shadow_.fn ? shadow_.fn(shadow_.ctx, x, t.end, delta1_, depthCutoff_)
                                 : opticalDepth(density_, x, t.end, delta1_);
    return std::exp(-sigmaT_ * tau);
  }
  /// V with every cone ignored (every light traced).
  Vec3 freeV(const Vec3& x, const Vec3& toViewer) const {
    Vec3 s(0.0f), a(0.0f);
    for (std::size_t i = 0; i < lights_.size(); ++i) {
      Term t;
      if (!term(i, x, toViewer, t)) continue;
      s += t.w * transmittance(x, t);
      a += t.w * t.m;
    }
    Vec3 v(0.0f);
    for (int c = 0; c < 3; ++c) v[c] = a[c] > 0.0f ? s[c] / a[c] : 0.0f;
    return v;
  }

  const std::vector<Light>& lights_;
  Phase phase_;
  float sigmaT_;
  const DensityGrid& density_;
  float delta1_;
  const SceneObjects* objects_;
  LampModel lamp_;
  ShadowDepthFn shadow_;  ///< the shadow rays' tracer, when given
  float depthCutoff_;     ///< τ at which it stops a shadow ray
  Vec3 lit_{0.0f};        ///< channels some light emits in
};

}  // namespace scatterlab
