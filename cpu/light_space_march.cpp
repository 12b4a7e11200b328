#include "cpu/light_space_march.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/stages.h"
#include "shading/transport.h"

namespace scatterlab {

LightSpaceMarcher::LightSpaceMarcher(const Scene& scene, const DensityGrid& density,
                                     const LightSpaceMarchSettings& settings, float delta1,
                                     const ShadowMapSettings& shadowMap)
    : scene_(scene), density_(density), s_(settings), delta1_(delta1) {
  if (s_.light == LightTransmittance::Mean) mean_ = scatterlab::meanDensity(density);
  if (scene.objects) shadows_ = std::make_unique<ShadowMap>(scene, shadowMap);
}

Vec3 LightSpaceMarcher::source(const Vec3& x, const Vec3& toViewer) const {
  const Medium& m = scene_.medium;
  Vec3 s(0.0f);
  for (std::size_t i = 0; i < scene_.lights.size(); ++i) {
    const Light& l = scene_.lights[i];
    Light::Incident inc;
    if (!l.incident(x, inc)) continue;
    const float vis = shadows_ ? shadows_->visibility(int(i), x) : 1.0f;
    if (vis <= 0.0f) continue;
    const float tau =
        s_.light == LightTransmittance::Mean
            ? mean_ * lengthInBox(l, inc, m.bounds, x)
            : opticalDepth(density_, x, lightSegmentEnd(l, inc, m.bounds, x), delta1_);
    s += inc.irradiance * (vis * m.phase.eval(-inc.toLight, toViewer) * std::exp(-m.sigmaT * tau));
  }
  return s;
}

LightSpaceMarcher::Pixel LightSpaceMarcher::march(const Ray& r, int first, int stride) const {
  const Medium& m = scene_.medium;
  const SceneObjects* objects = scene_.objects.get();
  Pixel px;
  SurfaceHit hit;
  const bool hasHit = objects && objects->intersect(r, 0.0f, kInfinity, hit);
  float T = 1.0f;
  float t0, t1;
  if (m.sigmaT > 0.0f && m.bounds.intersect(r, t0, t1) && t1 > t0) {
    if (hasHit) t1 = std::min(t1, hit.t);
    if (t1 > t0) {
      // N steps from the box entry to the surface or the box exit (the paper marches from the
      // surface towards the eye; the sum is the same, taken front to back here so that T_n is
      // the product of the steps before n).
      const int n = s_.steps;
      const float dt = (t1 - t0) / float(n);
      const Vec3 sc = density_.indexScale();
      const Vec3 u0 = r.at(t0 + 0.5f * dt) * sc + density_.indexOffset();
      const Vec3 du = r.dir * dt * sc;
      for (int i = 0; i < n; ++i) {
        const float D = density_.sampleIndex(u0 + float(i) * du);
        if (D <= 0.0f) continue;
        const float a = std::exp(-m.sigmaT * D * dt);
        if (i % stride == first) {
          const Vec3 p = r.at(t0 + (float(i) + 0.5f) * dt);
          px.inScatter += (T * m.albedo * (1.0f - a)) * source(p, -r.dir);
        }
        T *= a;
      }
    }
  }
  if (!hasHit) {
    px.boundary = T * scene_.background;
    px.alpha = 1.0f - T;
  } else {
    const SurfaceRadiance surface(scene_, density_, delta1_);
    px.boundary = T * surface(hit);
    px.alpha = 1.0f;
  }
  return px;
}

Image LightSpaceMarcher::render(Progress* progress) const {
  checkLightSpaceMarchScene(scene_, s_);
  const Camera& cam = scene_.camera;
  const auto rays = cam.rayGenerator();
  const int M = s_.interleave, stride = M * M;
  Image terms(cam.width, cam.height), img(cam.width, cam.height);
  img.alpha().assign(img.pixels().size(), 0.0f);
  if (progress) progress->restart("light-space march", cam.height);
  tbb::parallel_for(tbb::blocked_range<int>(0, cam.height), [&](const tbb::blocked_range<int>& rr) {
    for (int y = rr.begin(); y < rr.end(); ++y) {
      for (int x = 0; x < cam.width; ++x) {
        const Pixel p = march(rays(x, y), (x % M) + M * (y % M), stride);
        terms.at(x, y) = p.inScatter;
        img.at(x, y) = p.boundary;
        img.alpha()[std::size_t(y) * cam.width + x] = p.alpha;
      }
      if (progress) progress->advance(1);
    }
  });
  const Image sum = M == 1 ? std::move(terms) : blockSum(terms, M);
  for (std::size_t i = 0; i < img.pixels().size(); ++i) img.pixels()[i] += sum.pixels()[i];
  return img;
}

Image blockSum(const Image& terms, int m) {
  const int w = terms.width(), h = terms.height();
  Image row(w, h), out(w, h);
  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const int s = blockWindowStart(x, m, w);
      Vec3 sum(0.0f);
      for (int k = 0; k < m; ++k) sum += terms.at(s + k, y);
      row.at(x, y) = sum;
    }
  });
  tbb::parallel_for(0, h, [&](int y) {
    const int s = blockWindowStart(y, m, h);
    for (int x = 0; x < w; ++x) {
      Vec3 sum(0.0f);
      for (int k = 0; k < m; ++k) sum += row.at(x, s + k);
      out.at(x, y) = sum;
    }
  });
  return out;
}

namespace {

class LightSpaceMarchIntegrator : public Integrator {
 public:
  explicit LightSpaceMarchIntegrator(const PipelineSettings& s)
      : s_(s.integratorKeys.get<LightSpaceMarchSettings>()),
        delta1_(s.delta1),
        shadowMap_(s.shadowMap) {}
  bool needsRadiance() const override { return false; }
  Image integrate(Frame& frame, const Scene& scene, Progress* progress) override {
    checkLightSpaceMarchScene(scene, s_);
    const LightSpaceMarcher marcher(scene, frame.hostDensity(), s_, delta1_, shadowMap_);
    mean_ = marcher.meanDensity();
    shadowMaps_ = scene.objects ? int(scene.lights.size()) : 0;
    return marcher.render(progress);
  }
  void describe(RenderStats& st) const override {
    describeLightSpaceMarch(st, s_, mean_, shadowMaps_);
    // The CPU maps compare depths whatever render.shadow_map.type (VSM is GPU only).
    if (shadowMaps_ > 0) st.extra["shadow_map_lookup"] = "depth";
  }

 private:
  LightSpaceMarchSettings s_;
  float delta1_;
  ShadowMapSettings shadowMap_;
  float mean_ = 0.0f;
  int shadowMaps_ = 0;
};

}  // namespace

void registerLightSpaceMarch() {
  integrators().declare("light-space-march", lightSpaceMarchStage());
  integrators().addVariant("light-space-march", Backend::Cpu, [](const PipelineSettings& s) {
    return std::unique_ptr<Integrator>(new LightSpaceMarchIntegrator(s));
  });
}

}  // namespace scatterlab
