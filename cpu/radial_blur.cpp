#include "cpu/radial_blur.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "cpu/ray_marcher.h"
#include "shading/transport.h"

namespace scatterlab {

namespace {

/// Bilinear lookup of `img` at texel-space point (u, v) (texel centres at integers), edge
/// texels repeated: the GPU shader's twin (gpu/shaders/radial_blur.comp.glsl).
Vec3 bilinear(const Image& img, float u, float v) {
  const int w = img.width(), h = img.height();
  u = std::clamp(u, 0.0f, float(w - 1));
  v = std::clamp(v, 0.0f, float(h - 1));
  const int i0 = std::min(int(u), w - 1), j0 = std::min(int(v), h - 1);
  const int i1 = std::min(i0 + 1, w - 1), j1 = std::min(j0 + 1, h - 1);
  const float fu = u - float(i0), fv = v - float(j0);
  const Vec3 a = img.at(i0, j0) + (img.at(i1, j0) - img.at(i0, j0)) * fu;
  const Vec3 b = img.at(i0, j1) + (img.at(i1, j1) - img.at(i0, j1)) * fu;
  return a + (b - a) * fv;
}

/// Whether the view ray's first surface hides the light (an occluder of the pre-pass): a hit
/// nearer than the light (any hit for a directional light).
bool occludes(const Light& l, const Vec3& eye, float hitT) {
  return l.type == Light::Type::Directional || hitT < glm::length(l.position - eye);
}

}  // namespace

Image radialBlurPrePass(const Scene& scene, const DensityGrid& density, int light, int ds,
                        const MarchSettings& ms) {
  const Camera& cam = scene.camera;
  const Medium& m = scene.medium;
  const Light& l = scene.lights[std::size_t(light)];
  const auto rays = cam.rayGenerator();
  const int w = (cam.width + ds - 1) / ds, h = (cam.height + ds - 1) / ds;
  const SceneObjects* objects = scene.objects.get();
  Image pre(w, h);
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rr) {
    for (int j = rr.begin(); j < rr.end(); ++j)
      for (int i = 0; i < w; ++i) {
        const Ray r = rays.at((float(i) + 0.5f) * float(ds), (float(j) + 0.5f) * float(ds));
        float t0, t1;
        if (!(m.sigmaT > 0.0f && m.bounds.intersect(r, t0, t1) && t1 > t0)) continue;
        SurfaceHit hit;
        if (objects && objects->intersect(r, 0.0f, kInfinity, hit)) {
          if (occludes(l, r.origin, hit.t)) continue;  // occluder: black
          t1 = std::min(t1, hit.t);
          if (!(t1 > t0)) continue;
        }
        const int n = stepCount(t1 - t0, ms.step);
        const float dt = (t1 - t0) / float(n);
        const Vec3 sc = density.indexScale();
        const Vec3 u0 = r.at(t0 + 0.5f * dt) * sc + density.indexOffset();
        const Vec3 du = r.dir * dt * sc;
        Vec3 L(0.0f);
        float T = 1.0f;
        for (int k = 0; k < n && T > ms.minTransmittance; ++k) {
          const float D = density.sampleIndex(u0 + float(k) * du);
          if (D <= 0.0f) continue;
          const float a = std::exp(-m.sigmaT * D * dt);
          const Vec3 p = r.at(t0 + (float(k) + 0.5f) * dt);
          Light::Incident inc;
          if (l.incident(p, inc))
            L += (T * m.albedo * (1.0f - a) * m.phase.eval(-inc.toLight, -r.dir)) * inc.irradiance;
          T *= a;
        }
        pre.at(i, j) = L;
      }
  });
  return pre;
}

Image radialBlur(const Image& pre, int downsample, int width, int height, float ax, float ay,
                 const RadialBlurSettings& s) {
  Image out(width, height);
  const float ds = float(downsample);
  const float scale = s.exposure * s.weight / float(s.samples);
  tbb::parallel_for(0, height, [&](int y) {
    for (int x = 0; x < width; ++x) {
      const float fx = float(x) + 0.5f, fy = float(y) + 0.5f;
      const float dx = (fx - ax) * s.density / float(s.samples);
      const float dy = (fy - ay) * s.density / float(s.samples);
      Vec3 sum(0.0f);
      float decay = 1.0f;
      for (int i = 0; i < s.samples; ++i) {
        const float px = fx - float(i) * dx, py = fy - float(i) * dy;
        sum += decay * bilinear(pre, px / ds - 0.5f, py / ds - 0.5f);
        decay *= s.decay;
      }
      out.at(x, y) = sum * scale;
    }
  });
  return out;
}

Image renderRadialBlur(const Scene& scene, const DensityGrid& density, const RadialBlurSettings& s,
                       const MarchSettings& ms, float delta1) {
  checkRadialBlurScene(scene, s);
  const Camera& cam = scene.camera;
  // The base image: T·L0 along each view ray (the radiance source set to zero).
  const auto none = [](const Vec3&, const Vec3&) { return Vec3(0.0f); };
  Image img = marchImage(scene, density, none, ms, nullptr, delta1);
  for (int l = 0; l < int(scene.lights.size()); ++l) {
    float ax, ay;
    radialBlurLightPosition(scene, l, s.guardBand, ax, ay);
    const Image pre = radialBlurPrePass(scene, density, l, s.downsample, ms);
    const Image r = radialBlur(pre, s.downsample, cam.width, cam.height, ax, ay, s);
    for (std::size_t i = 0; i < img.pixels().size(); ++i) img.pixels()[i] += r.pixels()[i];
  }
  return img;
}

namespace {

class RadialBlurIntegrator : public Integrator {
 public:
  explicit RadialBlurIntegrator(const PipelineSettings& s)
      : s_(s.integratorKeys.get<RadialBlurSettings>()), march_(s.march), delta1_(s.delta1) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override {
    checkRadialBlurScene(scene, s_);
    if (progress) progress->restart("radial blur", 1);
    positions_ = Json::array();
    for (int l = 0; l < int(scene.lights.size()); ++l) {
      float x, y;
      radialBlurLightPosition(scene, l, s_.guardBand, x, y);
      positions_.push_back({x, y});
    }
    return renderRadialBlur(scene, frame.hostDensity(), s_, march_, delta1_);
  }
  void describe(RenderStats& st) const override { describeRadialBlur(st, s_, positions_); }

 private:
  RadialBlurSettings s_;
  MarchSettings march_;
  float delta1_;
  Json positions_ = Json::array();
};

}  // namespace

void registerRadialBlur() {
  integrators().declare("radial-blur", radialBlurStage());
  integrators().addVariant("radial-blur", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new RadialBlurIntegrator(s));
  });
}

}  // namespace scatterlab
