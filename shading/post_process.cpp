#include "shading/post_process.h"

#include <cmath>

namespace scatterlab {

namespace {

// The keys of `light-space-march` and `radial-blur`, each family's table beside its parser.

const std::vector<KeyDoc>& lightSpaceMarchKeys() {
  static const std::vector<KeyDoc> keys = {
      {"steps", "int", "128", "1…65536, at least interleave²",
       "N: terms of each view ray's sum, equal steps from the visible surface (or the box's far "
       "side) to the eye",
       "16"},
      {"interleave", "int", "4", "1…32, at most the image's width and height",
       "M: interleaved sampling in M×M pixel blocks; each pixel evaluates every M²-th term, "
       "then a separable M×M block sum (1: the plain march)",
       "2"},
      {"light_transmittance", "string", "mean", "mean, traced",
       "the light's transmittance: e^(−σt·D̄·d), D̄ the medium's mean density (Tóth & "
       "Umenhoffer's homogeneous model), or the real density traced with step delta1",
       R"("traced")"},
  };
  return keys;
}

void parseLightSpaceMarch(Params& p, const Scene&, PipelineSettings& settings) {
  LightSpaceMarchSettings s;
  s.steps = int(p.integer("steps", s.steps, Interval::closed(1, 65536)));
  s.interleave = int(p.integer("interleave", s.interleave, Interval::closed(1, 32)));
  if (s.interleave * s.interleave > s.steps)
    p.fail("interleave", "interleave² = " + std::to_string(s.interleave * s.interleave) +
                             " is more than steps = " + std::to_string(s.steps) +
                             ": some pixels of every block would evaluate no term; raise "
                             "render.steps or lower render.interleave");
  s.light = p.choice("light_transmittance", {"mean", "traced"}, "mean") == "mean"
                ? LightTransmittance::Mean
                : LightTransmittance::Traced;
  settings.integratorKeys.set(s);
}

const std::vector<KeyDoc>& radialBlurKeys() {
  static const std::vector<KeyDoc> keys = {
      {"samples", "int", "64", "1…4096", "n: samples per pixel along the screen ray to the light",
       "8"},
      {"density", "number", "1", "(0, 1]",
       "fraction of the pixel→light segment the n samples span (Mitchell's density)", "0.5"},
      {"weight", "number", "1", "[0, 1e6]", "scale of every sample", "2"},
      {"decay", "number", "1", "[0, 1]", "sample i is scaled by decay^i", "0.5"},
      {"exposure", "number", "1", "[0, 1e6]", "scale of the sum", "2"},
      {"downsample", "int", "1", "1, 2, 4", "the pre-pass has 1/downsample of the pixels per side",
       "2"},
      {"guard_band", "number", "0.5", "[0, 10]",
       "the light's screen position is clamped to this many image sizes beyond each edge", "1"},
  };
  return keys;
}

void parseRadialBlur(Params& p, const Scene&, PipelineSettings& settings) {
  RadialBlurSettings s;
  s.samples = int(p.integer("samples", s.samples, Interval::closed(1, 4096)));
  s.density = p.real("density", s.density, Interval{0.0, 1.0, true, false});
  s.weight = p.real("weight", s.weight, Interval::closed(0, 1e6));
  s.decay = p.real("decay", s.decay, Interval::closed(0, 1));
  s.exposure = p.real("exposure", s.exposure, Interval::closed(0, 1e6));
  s.downsample = int(p.integer("downsample", s.downsample, Interval::closed(1, 4)));
  if (s.downsample == 3) p.fail("downsample", "is 3; allowed: 1, 2, 4");
  s.guardBand = p.real("guard_band", s.guardBand, Interval::closed(0, 10));
  settings.integratorKeys.set(s);
}

}  // namespace

void describeLightSpaceMarch(RenderStats& st, const LightSpaceMarchSettings& s, float meanDensity,
                             int shadowMaps) {
  st.extra["steps"] = s.steps;
  st.extra["interleave"] = s.interleave;
  st.extra["terms_per_pixel"] =
      (s.steps + s.interleave * s.interleave - 1) / (s.interleave * s.interleave);
  st.extra["light_transmittance"] = s.light == LightTransmittance::Mean ? "mean" : "traced";
  if (s.light == LightTransmittance::Mean) st.extra["mean_density"] = meanDensity;
  st.extra["shadow_maps"] = shadowMaps;
}

void describeRadialBlur(RenderStats& st, const RadialBlurSettings& s, const Json& positions) {
  st.extra["samples_per_pixel"] = s.samples;
  st.extra["downsample"] = s.downsample;
  st.extra["light_screen_positions"] = positions;
}

namespace {

/// Its own steps (rays x steps / interleave^2 terms, each tracing the lights when
/// light_transmittance is traced) and, with scene objects, the CPU's shadow maps: up to 6
/// layers (a cube) per point or wide spot light, 1 per directional light.
StageWork lightSpaceMarchWork(const Scene& scene, const PipelineSettings& settings) {
  const auto& l = settings.integratorKeys.get<LightSpaceMarchSettings>();
  const Camera& c = scene.camera;
  const double rays = double(c.width) * c.height * c.spp;
  const double terms =
      rays * std::ceil(double(l.steps) / (double(l.interleave) * double(l.interleave)));
  StageWork w{.viewTerms = terms,
              .termsKey = "steps",
              .termsHow = std::to_string(c.width) + "x" + std::to_string(c.height) + " pixels x " +
                          std::to_string(c.spp) + " spp x " + std::to_string(l.steps) +
                          " steps / interleave " + std::to_string(l.interleave) + "^2"};
  if (l.light == LightTransmittance::Traced) {
    w.lightPoints = terms;
    w.lightWhat =
        "at every one of " + formatCount(terms) + " view-ray terms (light_transmittance traced)";
  }
  if (scene.objects) {
    double layers = 0;
    for (const Light& light : scene.lights)
      layers += light.type == Light::Type::Directional ? 1 : 6;
    const double r = settings.shadowMap.resolution;
    w.cpuArrays.push_back(
        {{"shadow_map.resolution"},
         "the shadow maps (" + formatCount(layers) + " layers of " + formatCount(r) + "^2 texels)",
         layers * r * r * sizeof(float)});
  }
  return w;
}

}  // namespace

const StageDecl& lightSpaceMarchStage() {
  static const StageDecl d{.keys = {{lightSpaceMarchKeys, parseLightSpaceMarch}},
                           .work = lightSpaceMarchWork};
  return d;
}

const StageDecl& radialBlurStage() {
  static const StageDecl d{.keys = {{radialBlurKeys, parseRadialBlur}}, .viewMarch = true};
  return d;
}

}  // namespace scatterlab
