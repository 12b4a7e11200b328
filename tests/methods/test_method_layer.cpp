/// The method layer: one registration per method, keys read once and the same on every backend,
/// overrides that behave like --set render.method, and the key lists the tolerance relies on.

#include <gtest/gtest.h>

#include <algorithm>

#include "api/scatterlab.h"
#include "core/stages.h"
#include "methods/pipeline.h"
#include "methods/register.h"
#include "methods/settings.h"
#include "support/scenes.h"

namespace scatterlab {
namespace {

using testing::kGlow;
const std::vector<std::string> kSmall = {"camera.width=24", "camera.height=18",
                                         "medium.resolution=16"};

std::vector<std::string> with(std::vector<std::string> sets) {
  sets.insert(sets.end(), kSmall.begin(), kSmall.end());
  return sets;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

bool gpuBackendBuilt() {
  initialize();
  return bool(backends()[int(Backend::Gpu)].makeFrame);
}

// The issue's first failure: a sampler key on a scene whose own method is `exact`, with the
// method chosen by override, failed with "unknown key 'render.sampler'".
TEST(MethodLayer, MethodOverrideMeansSetRenderMethod) {
  initialize();
  const std::string sampler = R"(render.sampler={"type": "gaussian-centres", "count": 3})";
  const Scene viaOverride = loadScene(kGlow, with({sampler}));
  const Scene viaSet = loadScene(kGlow, with({sampler, "render.method=gradient"}));
  const RenderResult a = createMethod(viaOverride, "gradient", "cpu")->render(viaOverride, nullptr);
  const RenderResult b = createMethod(viaSet, "", "cpu")->render(viaSet, nullptr);
  EXPECT_EQ(a.stats.method, "gradient");
  EXPECT_EQ(a.stats.samples, 3);
  EXPECT_EQ(a.image.pixels(), b.image.pixels());
  // And an error is the same error either way.
  const Scene badO = loadScene(kGlow, with({"render.sampler.count=0"}));
  const Scene badS = loadScene(kGlow, with({"render.sampler.count=0", "render.method=gradient"}));
  const std::string eo = errorOf([&] { createMethod(badO, "gradient", "cpu"); });
  EXPECT_NE(eo.find("render.sampler.count"), std::string::npos) << eo;
  EXPECT_EQ(eo, errorOf([&] { createMethod(badS, "", "cpu"); }));
}

// The second failure: `slicing` was valid with --backend gpu and rejected with --backend cpu.
TEST(MethodLayer, SameKeysOnEveryBackend) {
  initialize();
  for (const MethodDesc& d : builtinMethods()) {
    if (!d.radianceVolume()) continue;
    const Scene s = loadScene(kGlow, with({"render.method=" + d.name, "render.slicing=view-planes",
                                           "render.levels=[4]"}));
    auto cpu = createMethod(s, "", "cpu");
    if (d.name == "per-voxel" || d.name == "gradient") {
      const RenderResult r = cpu->render(s, nullptr);
      ASSERT_TRUE(r.stats.extra.contains("unused_keys")) << d.name;
      EXPECT_EQ(r.stats.extra["unused_keys"], Json::array({"render.slicing"})) << d.name;
    }
    if (gpuBackendBuilt() && pipelineRunsOn(d, Backend::Gpu)) {
      EXPECT_NO_THROW(createMethod(s, "", "gpu")) << d.name;  // creating needs no context
    }
  }
  // A bad value is the same error on both backends (read before the backend is chosen).
  const Scene bad = loadScene(kGlow, with({"render.method=gradient", "render.slicing=diagonal"}));
  const std::string ec = errorOf([&] { createMethod(bad, "", "cpu"); });
  EXPECT_NE(ec.find("render.slicing"), std::string::npos) << ec;
  if (gpuBackendBuilt()) {
    EXPECT_EQ(ec, errorOf([&] { createMethod(bad, "", "gpu"); }));
  }
}

TEST(MethodLayer, ABackendWithoutAVariantIsAClearError) {
  initialize();
  const Scene s = loadScene(kGlow, kSmall);
  if (!gpuBackendBuilt()) GTEST_SKIP() << "built without the GPU backend";
  const std::string e = errorOf([&] { createMethod(s, "exact", "gpu"); });
  EXPECT_NE(e.find("'exact' has no GPU variant"), std::string::npos) << e;
  // auto falls back to the CPU for a CPU-only method, whatever the machine.
  const RenderResult r = createMethod(s, "exact", "auto")->render(s, nullptr);
  EXPECT_EQ(r.stats.backend, "cpu");
}

// The third failure: a fractional radiance resolution rendered at the truncated size.
TEST(MethodLayer, ResolutionsFollowOneRule) {
  initialize();
  const Scene s =
      loadScene(kGlow, with({"render.method=per-voxel", "render.radiance_resolution=[8,8,8.7]"}));
  const std::string e = errorOf([&] { createMethod(s, "", "cpu"); });
  EXPECT_NE(e.find("'render.radiance_resolution': expected integers"), std::string::npos) << e;
  const std::string m = errorOf([&] { loadScene(kGlow, {"medium.resolution=[8,8,8.7]"}); });
  EXPECT_NE(m.find("'medium.resolution': expected integers"), std::string::npos) << m;
  const Scene ok =
      loadScene(kGlow, with({"render.method=per-voxel", "render.radiance_resolution=[8,6,4]"}));
  const RenderResult r = createMethod(ok, "", "cpu")->render(ok, nullptr);
  EXPECT_EQ(r.stats.extra["radiance_resolution"], Json::array({8, 6, 4}));
  EXPECT_EQ(r.radiance->dims(), IVec3(8, 6, 4));
}

TEST(MethodLayer, KeysOfOtherMethodsAreIgnoredAndListedUnknownKeysAreErrors) {
  initialize();
  const Scene s = loadScene(kGlow, with({"render.method=adaptive", "render.delta2=0.01",
                                         "render.epsilon=0.5", "render.sampler.count=4"}));
  auto exact = createMethod(s, "exact", "cpu");
  EXPECT_EQ(exact->ignoredKeys,
            (std::vector<std::string>{"render.delta2", "render.epsilon", "render.sampler"}));
  EXPECT_EQ(createMethod(s, "adaptive", "cpu")->ignoredKeys, std::vector<std::string>{});
  const RenderResult r = exact->render(s, nullptr);
  EXPECT_EQ(r.stats.extra["ignored_keys"].size(), 3u);
  const Scene bogus = loadScene(kGlow, with({"render.bogus=1"}));
  const std::string e = errorOf([&] { createMethod(bogus, "exact", "cpu"); });
  EXPECT_NE(e.find("unknown key 'render.bogus'"), std::string::npos) << e;
}

// render.shadow_map (the GPU's shadow maps of scene objects) is read with the other pipeline
// keys on every backend: a bad value or an unknown key is an error naming it, and the
// values reach the settings.
TEST(MethodLayer, ShadowMapKeysAreValidatedOnEveryBackend) {
  initialize();
  const auto error = [](const std::string& set) {
    const Scene s = loadScene(kGlow, with({"render.method=per-voxel", set}));
    return errorOf([&] { createMethod(s, "", "cpu"); });
  };
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"render.shadow_map.type=\"pcss\"", "'render.shadow_map.type'"},
      {"render.shadow_map.resolution=8", "'render.shadow_map.resolution'"},
      {"render.shadow_map.resolution=5000", "'render.shadow_map.resolution'"},
      {"render.shadow_map.bias=-1", "'render.shadow_map.bias'"},
      {"render.shadow_map.filter=4", "'render.shadow_map.filter'"},
      {"render.shadow_map.bleed_reduction=1", "'render.shadow_map.bleed_reduction'"},
      {"render.shadow_map.blur=3", "render.shadow_map.blur"},
      {"render.shadow_map=3", "render.shadow_map"},
  };
  for (const auto& [set, key] : bad) {
    const std::string e = error(set);
    EXPECT_NE(e.find(key), std::string::npos) << set << ": " << e;
  }
  const Scene s = loadScene(kGlow, with({"render.method=per-voxel",
                                         "render.shadow_map={\"type\": \"depth\", "
                                         "\"resolution\": 64, \"filter\": 5, \"bias\": 2}"}));
  Params p(s.render, "render");
  const PipelineSettings ps = parsePipelineSettings(p, s, builtinMethods()[1]);
  EXPECT_EQ(ps.shadowMap.type, ShadowMapSettings::Type::Depth);
  EXPECT_EQ(ps.shadowMap.resolution, 64);
  EXPECT_EQ(ps.shadowMap.filter, 5);
  EXPECT_EQ(ps.shadowMap.bias, 2.0f);
  EXPECT_FLOAT_EQ(ps.shadowMap.bleedReduction, 0.2f);
  EXPECT_TRUE(ps.shadowMap.given);
}

const MethodDesc& rowNamed(const std::string& name) {
  for (const MethodDesc& d : builtinMethods())
    if (d.name == name) return d;
  throw std::logic_error("no row " + name);
}

// The plan resolves the stages that run once, the chosen ones: render.integrator replaces the
// row's integrator in the plan's declarations, so its facts (here exact's light march at every
// view step) are what the checks read; the sampler is built and its count planned.
TEST(MethodLayer, ThePlanHoldsTheChosenStages) {
  initialize();
  const Scene s = loadScene(kGlow, with({"render.integrator=\"exact\""}));
  Params p(s.render, "render");
  const MethodPlan plan = planMethod(rowNamed("per-voxel"), p, s, Backend::Cpu);
  EXPECT_EQ(plan.integrator, "exact");
  ASSERT_NE(plan.integratorDecl, nullptr);
  EXPECT_EQ(plan.integratorDecl, plan.stages.back());
  EXPECT_EQ(plan.integratorDecl->lightWork, LightWork::EveryViewStep);
  EXPECT_EQ(plan.stages.size(), 2u);  // reconstruction, integrator
  const Scene g = loadScene(kGlow, with({}));
  Params q(g.render, "render");
  const MethodPlan gradient = planMethod(rowNamed("gradient"), q, g, Backend::Cpu);
  EXPECT_EQ(gradient.evaluator, "volume-tracer");
  EXPECT_EQ(gradient.integrator, "ray-marcher");
  ASSERT_TRUE(gradient.sampler);
  EXPECT_EQ(gradient.samplerType, "jittered");
  EXPECT_EQ(gradient.plannedSamples, gradient.sampler->plannedCount(g));
  EXPECT_GT(gradient.plannedSamples, 0);
  // The work bound follows the chosen integrator: 2000 x 1500 rays at a step of 1e-3 are
  // 5.2e9 view steps (within kMaxViewSteps, so per-voxel's ray-marcher passes), but exact's
  // shadow rays at each of them, 222 steps each at 128³, are 1.15e12 (above kMaxLightSteps).
  const std::vector<std::string> big = {"camera.width=2000", "camera.height=1500",
                                        "render.march_step=1e-3"};
  std::vector<std::string> bigExact = big;
  bigExact.push_back("render.integrator=\"exact\"");
  const Scene marched = loadScene(kGlow, big), traced = loadScene(kGlow, bigExact);
  Params r(marched.render, "render"), e(traced.render, "render");
  EXPECT_NO_THROW(planMethod(rowNamed("per-voxel"), r, marched, Backend::Cpu));
  try {
    planMethod(rowNamed("per-voxel"), e, traced, Backend::Cpu);
    ADD_FAILURE() << "exact's light work was not bounded";
  } catch (const LimitError& err) {
    EXPECT_NE(std::string(err.what()).find("'render.delta1'"), std::string::npos) << err.what();
  }
}

// Which keys a backend does not read is decided once, in the plan, from the rows' `only`:
// the GPU's keys on the CPU, slicing under the GPU's compute pipeline only, the CPU march's
// on the GPU. (Planning builds no variant, so this needs no GPU.)
TEST(MethodLayer, UnusedKeysPerBackendComeFromThePlan) {
  initialize();
  const auto unused = [](const std::vector<std::string>& sets, Backend b) {
    const Scene s = loadScene(kGlow, with(sets));
    Params p(s.render, "render");
    return planMethod(rowNamed("gradient"), p, s, b).unusedKeys;
  };
  using V = std::vector<std::string>;
  const V gpuKeys = {"render.gpu_pipeline=\"raster\"", "render.slicing=\"view-planes\""};
  EXPECT_EQ(unused(gpuKeys, Backend::Cpu), (V{"render.gpu_pipeline", "render.slicing"}));
  EXPECT_EQ(unused(gpuKeys, Backend::Gpu), V{});
  EXPECT_EQ(unused({"render.slicing=\"view-planes\""}, Backend::Gpu), V{"render.slicing"});
  const V cpuKeys = {"render.fast_march=false", "render.march_simd=\"sse2\""};
  EXPECT_EQ(unused(cpuKeys, Backend::Gpu), (V{"render.fast_march", "render.march_simd"}));
  EXPECT_EQ(unused(cpuKeys, Backend::Cpu), V{});
}

// methodKeys() (what the tolerance of other methods' keys uses) is exactly what each method's
// parser reads from an empty render object.
TEST(MethodLayer, KeyListsAreWhatTheParsersRead) {
  initialize();
  for (const MethodDesc& d : builtinMethods()) {
    const Scene s = loadScene(kGlow, with({"render.method=" + d.name}));
    std::set<std::string> read;
    {
      Params::ReadLog log;
      createMethod(s, "", "cpu");
      for (const std::string& k : log.keys())
        if (k.rfind("render.", 0) == 0 && k.find('.', 7) == std::string::npos)
          read.insert(k.substr(7));
    }
    std::set<std::string> listed = {"method", "backend"};
    for (const std::string& k : methodKeys(d)) listed.insert(k);
    EXPECT_EQ(read, listed) << d.name;
    EXPECT_EQ(methods().get(d.name, "").keys, methodKeys(d)) << d.name;
  }
}

/// The stages a method's row composes, in the order the pipeline runs them (methods/pipeline.cpp):
/// what a new row in builtinMethods() is held to without editing this file.
std::vector<std::string> stagesOf(const MethodDesc& d) {
  std::vector<std::string> stages{"density"};
  if (d.sampler) {
    stages.push_back("sampling");
    stages.push_back(d.refiner.empty() ? "evaluation" : "dynamic_sampling");
  }
  if (d.radianceVolume()) stages.push_back(d.sampler ? "reconstruction" : "radiance");
  stages.push_back("march");
  return stages;
}

// Every registered method renders on the CPU through the one pipeline, with the stages its row
// in the method table composes timed, and a radiance volume exactly where it builds one.
TEST(MethodLayer, EveryMethodRunsItsStageSequence) {
  initialize();
  ASSERT_EQ(methods().names().size(), builtinMethods().size());
  // Spot checks of the rule on the paper's methods.
  const auto desc = [](const std::string& name) {
    for (const MethodDesc& d : builtinMethods())
      if (d.name == name) return d;
    throw std::logic_error("no method " + name);
  };
  EXPECT_EQ(stagesOf(desc("per-voxel")),
            (std::vector<std::string>{"density", "radiance", "march"}));
  EXPECT_EQ(stagesOf(desc("adaptive")),
            (std::vector<std::string>{"density", "sampling", "dynamic_sampling", "reconstruction",
                                      "march"}));
  EXPECT_EQ(stagesOf(desc("exact")), (std::vector<std::string>{"density", "march"}));
  for (const MethodDesc& d : builtinMethods()) {
    // radial-blur refuses glow's lamp inside the medium: the lamp behind the box for it.
    std::vector<std::string> sets = {"render.levels=[4]", "render.voxel_switch=0"};
    if (d.name == "radial-blur") sets.push_back("lights.0.position=[0.52,0.5,1.4]");
    const Scene s = loadScene(kGlow, with(sets));
    const RenderResult r = createMethod(s, d.name, "cpu")->render(s, nullptr);
    std::vector<std::string> got;
    for (const auto& [stage, ms] : r.stats.timingsMs) got.push_back(stage);
    EXPECT_EQ(got, stagesOf(d)) << d.name;
    EXPECT_EQ(r.stats.device, "CPU (TBB)");
    ASSERT_TRUE(r.density) << d.name;
    EXPECT_EQ(bool(r.radiance), d.radianceVolume()) << d.name;
  }
}

}  // namespace
}  // namespace scatterlab

namespace scatterlab {
namespace {

// Issue 25: a backend string other than cpu, gpu, auto ("GPU", "cuda", "") used to run on
// auto without a word; now it is an error listing the three, before any work.
TEST(MethodLayer, UnknownBackendsAreErrorsListingTheAllowedOnes) {
  initialize();
  const Scene s = loadScene(kGlow, with({}));
  for (const std::string b : {"GPU", "cuda", "", "cpu ", "Auto"}) {
    const std::string e = errorOf([&] { createMethod(s, "per-voxel", b); });
    EXPECT_NE(e.find("backend: unknown backend '" + b + "'"), std::string::npos) << e;
    EXPECT_NE(e.find("allowed: 'cpu', 'gpu', 'auto'"), std::string::npos) << e;
  }
  EXPECT_NE(errorOf([&] { createMethod(s, "per-voxel", "GPU"); }).find("(did you mean 'gpu'?)"),
            std::string::npos);
  EXPECT_EQ(errorOf([&] { createMethod(s, "per-voxel", "cuda"); }).find("did you mean"),
            std::string::npos);
  // Through the Renderer too (the Python module's path).
  const std::string r =
      errorOf([&] { Renderer::fromFile(kGlow, kSmall, "per-voxel", "cuda").render(); });
  EXPECT_NE(r.find("unknown backend 'cuda'"), std::string::npos) << r;
  // The three allowed ones are accepted.
  for (const std::string b : {"cpu", "auto"}) EXPECT_NO_THROW(createMethod(s, "per-voxel", b)) << b;
  // A misspelt method names the argument ('method'), not a tool flag, and the likely one.
  const std::string m = errorOf([&] { createMethod(s, "per-voxle", "cpu"); });
  EXPECT_EQ(
      m.rfind("'method': unknown method 'per-voxle' (did you mean 'per-voxel'?); allowed: ", 0), 0u)
      << m;
}

}  // namespace
}  // namespace scatterlab

namespace scatterlab::testing {
namespace {

// Issue 38: a stage's variant can only be added to a name its family declared (a misspelt name
// in a register function fails at initialize(), instead of a stage without keys or docs).
TEST(MethodLayer, AVariantOfANameNeverDeclaredIsRefused) {
  StageRegistry<IntegratorMaker> r("test integrator");
  try {
    r.addVariant("ray-marchr", Backend::Gpu, {});
    FAIL() << "no error";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("'ray-marchr', which no stage declares"),
              std::string::npos)
        << e.what();
  }
  r.declare("ray-marcher", {});
  r.addVariant("ray-marcher", Backend::Cpu, [](const PipelineSettings&) { return nullptr; });
  EXPECT_TRUE(r.get("ray-marcher", "integrator").has(Backend::Cpu));
  EXPECT_FALSE(r.get("ray-marcher", "integrator").has(Backend::Gpu));
}

}  // namespace
}  // namespace scatterlab::testing
