// The experiment's plan: parsing and validating a config (scenes, references, methods, sweeps
// and their axes), expanding it into runs with their configuration hashes, and building a run's
// scene (including the lights axis's ring of replicated lights).

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/scene.h"
#include "core/suggest.h"
#include "experiment/detail.h"

namespace scatterlab {

namespace fs = std::filesystem;
using detail::fileSafe;
using detail::readText;
using detail::valueLabel;

std::string stableHash(const std::string& text) {
  unsigned long long h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char b[17];
  std::snprintf(b, sizeof b, "%016llx", h);
  return b;
}

namespace {

std::vector<std::string> stringList(Params& p, const std::string& key) {
  std::vector<std::string> out;
  if (!p.has(key)) {
    p.allow(key);
    return out;
  }
  const Json& j = p.raw(key);
  if (!j.is_array()) p.fail(key, "expected an array of strings, got " + describeValue(j));
  for (const Json& v : j) {
    if (!v.is_string()) p.fail(key, "expected an array of strings, got " + describeValue(v));
    out.push_back(v.get<std::string>());
  }
  return out;
}

/// A "set" list: strings, each a KEY=VALUE override (checked before any run: issue 37).
std::vector<std::string> overrideList(Params& p, const std::string& key) {
  std::vector<std::string> out = stringList(p, key);
  for (const std::string& a : out) {
    try {
      checkOverrideSyntax(a);
    } catch (const ConfigError& e) {
      p.fail(key, e.what());
    }
  }
  return out;
}

bool safeName(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!std::isalnum((unsigned char)c) && c != '-' && c != '_' && c != '.') return false;
  return true;
}

void checkName(Params& p, const std::string& key, const std::string& name) {
  if (!safeName(name))
    p.fail(key, "'" + name +
                    "' must be non-empty and use only letters, digits, '-', '_' and '.' "
                    "(it names files)");
}

/// A method entry: a string (its name = the method) or an object.
MethodSpec parseMethod(const Json& j, const std::string& path, const std::string& defBackend,
                       bool reference = false) {
  MethodSpec m;
  if (j.is_string()) {
    m.name = m.method = j.get<std::string>();
    m.backend = defBackend;
  } else {
    Params r(j, path);
    m.method = r.string("method");
    m.name = r.string("name", m.method);
    m.backend = r.choice("backend", {"cpu", "gpu", "auto"}, defBackend);
    m.sets = overrideList(r, "set");
    if (r.has("paper_rel_error"))
      m.paper["rel_error"] = r.number("paper_rel_error", std::nullopt, Interval::atLeast(0));
    else
      r.allow("paper_rel_error");
    if (r.has("paper_samples"))
      m.paper["samples"] = r.number("paper_samples", std::nullopt, Interval::atLeast(0));
    else
      r.allow("paper_samples");
    if (reference)
      m.converge = r.boolean("converge", false);
    else if (r.has("converge"))
      r.fail("converge", "only references are converged (put the method in 'references')");
    checkName(r, "name", m.name);
    r.finish();
  }
  if (!methods().contains(m.method)) {
    std::string list;
    for (const auto& n : methods().names()) list += (list.empty() ? "'" : ", '") + n + "'";
    throw ConfigError("'" + path + (j.is_string() ? "" : ".method") + "': unknown method '" +
                      m.method + "'" + didYouMean(m.method, methods().names()) +
                      "; allowed: " + list);
  }
  if (!safeName(m.name))
    throw ConfigError("'" + path + "': method name '" + m.name + "' is not file-name safe");
  return m;
}

/// One value of a named axis (resolution, samples, lights, image_size, epsilon) or of a dotted
/// scene key; `bad` throws.
template <class Bad>
AxisValue parseAxisValue(const std::string& name, const Json& v, const Bad& bad) {
  AxisValue av;
  av.value = v;
  const auto positiveInt = [&](const Json& x) {
    return x.is_number_integer() && x.get<long long>() >= 1;
  };
  if (name == "resolution") {
    if (!(positiveInt(v) || (v.is_array() && v.size() == 3 && positiveInt(v[0]) &&
                             positiveInt(v[1]) && positiveInt(v[2]))))
      bad("expected a positive integer or [nx, ny, nz]");
    av.sets.push_back("medium.resolution=" + v.dump());
  } else if (name == "samples") {
    if (!positiveInt(v)) bad("expected a positive integer (render.sampler.count)");
    av.sets.push_back("render.sampler.count=" + v.dump());
    av.affectsReference = false;
  } else if (name == "epsilon") {
    if (!v.is_number() || v.get<double>() < 0) bad("expected a number >= 0 (render.epsilon)");
    av.sets.push_back("render.epsilon=" + v.dump());
    av.affectsReference = false;
  } else if (name == "lights") {
    if (!positiveInt(v) || v.get<long long>() > 4096) bad("expected an integer in [1, 4096]");
    av.lights = int(v.get<long long>());
  } else if (name == "image_size") {
    if (!(v.is_array() && v.size() == 2 && positiveInt(v[0]) && positiveInt(v[1])))
      bad("expected [width, height]");
    av.sets.push_back("camera.width=" + v[0].dump());
    av.sets.push_back("camera.height=" + v[1].dump());
  } else {
    av.sets.push_back(name + "=" + v.dump());
    av.affectsReference = name.rfind("render.", 0) != 0;
  }
  return av;
}

/// Parses one axis: a named one (resolution, samples, lights, image_size, epsilon) or a dotted
/// scene key.
Axis parseAxis(Params& ax, const std::string& name) {
  const Json& vals = ax.raw(name);
  const std::string key = ax.keyPath(name);
  if (!vals.is_array() || vals.empty())
    throw ConfigError("'" + key + "': a sweep axis is a non-empty array of values, got " +
                      describeValue(vals));
  static const std::set<std::string> named = {"resolution", "samples", "lights", "image_size",
                                              "epsilon"};
  if (!named.count(name) && name.find('.') == std::string::npos)
    throw ConfigError("'" + key + "': unknown sweep axis '" + name + "'" +
                      didYouMean(name, std::vector<std::string>(named.begin(), named.end())) +
                      "; allowed: resolution, samples, lights, image_size, epsilon, or a dotted "
                      "scene key such as render.sampler.radius_scale");
  if (!named.count(name)) {
    try {
      checkOverrideSyntax(name + "=0");
    } catch (const ConfigError&) {
      throw ConfigError("'" + key + "': sweep axis '" + name +
                        "' is not a dotted scene key (an empty part, or deeper than " +
                        std::to_string(kMaxJsonDepth) + " levels)");
    }
  }
  Axis a;
  a.name = name;
  for (const Json& v : vals)
    a.values.push_back(parseAxisValue(name, v, [&](const std::string& what) {
      throw ConfigError("'" + key + "': bad value " + describeValue(v) + ": " + what);
    }));
  return a;
}

/// 'scene' (one file) or 'scenes' (named entries with their own overrides); names unique.
void parseScenes(Params& p, const fs::path& base, ExperimentPlan& plan) {
  const auto resolve = [&](const std::string& f) {
    return fs::path(f).is_absolute() ? f : (base / f).lexically_normal().string();
  };
  if (p.has("scene") && p.has("scenes")) p.fail("scenes", "give either 'scene' or 'scenes'");
  if (p.has("scene")) {
    SceneSpec s;
    s.file = resolve(p.string("scene"));
    s.name = fileSafe(fs::path(s.file).stem().string());
    plan.scenes.push_back(s);
    p.allow("scenes");
  } else {
    p.allow("scene");
    for (Params s : p.children("scenes", true)) {
      SceneSpec sc;
      sc.file = resolve(s.string("file"));
      sc.name = s.string("name", fileSafe(fs::path(sc.file).stem().string()));
      checkName(s, "name", sc.name);
      sc.sets = overrideList(s, "set");
      s.finish();
      plan.scenes.push_back(sc);
    }
    if (plan.scenes.empty()) p.fail("scenes", "give at least one scene");
  }
  std::set<std::string> seen;
  for (const SceneSpec& s : plan.scenes) {
    if (!seen.insert(s.name).second) p.fail("scenes", "two scenes are named '" + s.name + "'");
    checkReadableFile(s.file, "scene file");
  }
}

/// 'references' (CPU unless they say otherwise) and 'methods' (or its synonym 'runs').
void parseMethods(Params& p, const std::string& defBackend, ExperimentPlan& plan) {
  if (!p.has("references")) {
    // The default: `exact` at half a voxel, checked by halving once more (docs/metrics.md).
    p.allow("references");
    MethodSpec ref;
    ref.name = ref.method = "exact";
    ref.backend = "cpu";
    ref.converge = true;
    plan.references.push_back(ref);
    plan.defaultReference = true;
  } else {
    const Json& refs = p.raw("references");
    if (!refs.is_array() || refs.empty())
      p.fail("references", "expected a non-empty array of methods, got " + describeValue(refs));
    for (std::size_t i = 0; i < refs.size(); ++i)
      plan.references.push_back(parseMethod(
          refs[i], p.keyPath("references") + "[" + std::to_string(i) + "]", "cpu", true));
  }

  const std::string methodsKey = p.has("runs") && !p.has("methods") ? "runs" : "methods";
  if (p.has("runs") && p.has("methods")) p.fail("runs", "give either 'methods' or 'runs'");
  p.allow(methodsKey == "runs" ? "methods" : "runs");
  if (!p.has(methodsKey)) p.fail("methods", "give at least one method to run");
  const Json& ms = p.raw(methodsKey);
  if (!ms.is_array() || ms.empty())
    p.fail(methodsKey, "expected a non-empty array of methods, got " + describeValue(ms));
  std::set<std::string> seen;
  for (std::size_t i = 0; i < ms.size(); ++i) {
    const std::string key = p.keyPath(methodsKey) + "[" + std::to_string(i) + "]";
    MethodSpec m = parseMethod(ms[i], key, defBackend);
    if (!seen.insert(m.name).second)
      throw ConfigError("'" + key + "': two methods are named '" + m.name +
                        "'; give them distinct 'name's");
    plan.methods.push_back(std::move(m));
  }
}

bool hasMethod(const ExperimentPlan& plan, const std::string& name) {
  return std::any_of(plan.methods.begin(), plan.methods.end(),
                     [&](const MethodSpec& x) { return x.name == name; });
}

/// One entry of 'sweeps'; `index` names it when it has no name, `seen` holds the names of the
/// sweeps before it.
SweepSpec parseSweep(Params& s, std::size_t index, const ExperimentPlan& plan, int defReps,
                     int defWarm, int defSteady, std::set<std::string>& seen) {
  SweepSpec sp;
  sp.name = s.string("name", "sweep" + std::to_string(index));
  checkName(s, "name", sp.name);
  if (!seen.insert(sp.name).second) s.fail("name", "two sweeps are named '" + sp.name + "'");
  if (s.has("axes")) {
    Params ax = s.child("axes");
    for (auto it = ax.json().begin(); it != ax.json().end(); ++it)
      sp.axes.push_back(parseAxis(ax, it.key()));
    ax.finish();
  } else {
    s.allow("axes");
  }
  sp.methods = stringList(s, "methods");
  for (const std::string& m : sp.methods)
    if (!hasMethod(plan, m))
      s.fail("methods", "'" + m + "' is not the name of an entry of 'methods'");
  sp.scenes = stringList(s, "scenes");
  for (const std::string& n : sp.scenes)
    if (std::none_of(plan.scenes.begin(), plan.scenes.end(),
                     [&](const SceneSpec& x) { return x.name == n; }))
      s.fail("scenes", "'" + n + "' is not the name of an entry of 'scenes'");
  sp.repetitions = int(s.integer("repetitions", defReps, Interval::closed(1, 1000)));
  sp.warmup = int(s.integer("warmup", defWarm, Interval::closed(0, 100)));
  sp.steadyFrames = int(s.integer("steady_frames", defSteady, Interval::closed(0, 10000)));
  sp.baseline = s.string("baseline", std::string());
  if (!sp.baseline.empty() && !hasMethod(plan, sp.baseline))
    s.fail("baseline", "'" + sp.baseline + "' is not the name of an entry of 'methods'");
  if (s.has("paper_fps")) {
    sp.paperFps = s.raw("paper_fps");
    if (!sp.paperFps.is_object()) s.fail("paper_fps", "expected {method name: [fps, ...]}");
  } else {
    s.allow("paper_fps");
  }
  s.finish();
  return sp;
}

/// 'sweeps', or one sweep "main" without axes when the config gives none.
void parseSweeps(Params& p, ExperimentPlan& plan, int defReps, int defWarm, int defSteady) {
  if (!p.has("sweeps")) {
    p.allow("sweeps");
    SweepSpec sp;
    sp.name = "main";
    sp.repetitions = defReps;
    sp.warmup = defWarm;
    sp.steadyFrames = defSteady;
    plan.sweeps.push_back(sp);
    return;
  }
  const Json& sw = p.raw("sweeps");
  if (!sw.is_array() || sw.empty())
    p.fail("sweeps", "expected a non-empty array of sweep objects, got " + describeValue(sw));
  std::set<std::string> seen;
  for (std::size_t i = 0; i < sw.size(); ++i) {
    Params s(sw[i], p.keyPath("sweeps") + "[" + std::to_string(i) + "]");
    plan.sweeps.push_back(parseSweep(s, i, plan, defReps, defWarm, defSteady, seen));
  }
}

/// The hash of everything that determines a run's result (its record is reused while it
/// matches).
std::string runHash(const ExperimentPlan& plan, const RunSpec& r, const std::string& sceneHash) {
  const MethodSpec& m = *r.spec;
  Json key = {{"scene", sceneHash},
              {"sets", r.sets},
              {"backend", m.backend},
              {"method", m.method},
              {"repetitions", r.sweepSpec->repetitions},
              {"warmup", r.sweepSpec->warmup},
              {"lights", r.lights ? Json(*r.lights) : Json()}};
  if (r.sweepSpec->steadyFrames > 0) key["steady_frames"] = r.sweepSpec->steadyFrames;
  Json refs = Json::array();
  for (const MethodSpec& ref : plan.references)
    refs.push_back(ref.converge ? Json{ref.method, ref.backend, ref.sets, "converge"}
                                : Json{ref.method, ref.backend, ref.sets});
  key["references"] = refs;
  if (plan.maskRadius) key["mask_radius"] = *plan.maskRadius;
  key["ref_sets"] = r.refSets;
  return stableHash(key.dump());
}

/// The run of method `m` on scene `sc` at point `pt` of sweep `sw`, whose axis values are `vals`.
RunSpec makeRun(const ExperimentPlan& plan, const SweepSpec& sw, const SceneSpec& sc,
                std::size_t pt, const std::vector<const AxisValue*>& vals, const MethodSpec& m,
                const std::vector<std::string>& globalSets) {
  RunSpec r;
  r.sweep = sw.name;
  r.scene = sc.name;
  r.method = m.name;
  r.spec = &m;
  r.sceneSpec = &sc;
  r.sweepSpec = &sw;
  r.point = int(pt);
  // Order: scene's sets, global sets (+ --set), the run's method, the method's own sets, then
  // the sweep point. References get the same minus the method and the render.* axes (sample
  // budget, ε), so that one reference serves every budget.
  r.sets = sc.sets;
  r.sets.insert(r.sets.end(), globalSets.begin(), globalSets.end());
  r.refSets = r.sets;
  r.sets.push_back("render.method=" + m.method);
  r.sets.insert(r.sets.end(), m.sets.begin(), m.sets.end());
  std::string id = (plan.sweeps.size() > 1 ? sw.name + "__" : "") +
                   (plan.scenes.size() > 1 ? sc.name + "__" : "") + m.name;
  for (std::size_t k = 0; k < sw.axes.size(); ++k) {
    const AxisValue& v = *vals[k];
    r.axes[sw.axes[k].name] = v.value;
    r.sets.insert(r.sets.end(), v.sets.begin(), v.sets.end());
    if (v.affectsReference)
      r.refSets.insert(r.refSets.end(), v.sets.begin(), v.sets.end());
    else
      r.axesAllAffectReference = false;
    if (v.lights) r.lights = r.refLights = v.lights;
    id += "__" + fileSafe(sw.axes[k].name) + "-" + fileSafe(valueLabel(v.value));
  }
  r.id = id;
  r.paperFps = sw.paperFps.contains(m.name) ? sw.paperFps[m.name][pt] : Json(nullptr);
  return r;
}

/// Most runs one experiment may plan (each is a render and a record on disk).
constexpr std::size_t kMaxExperimentRuns = 100000;

/// Expands the plan into runs: sweep × scene × point (last axis fastest) × method.
void expandRuns(ExperimentPlan& plan, const std::vector<std::string>& globalSets) {
  std::set<std::string> ids;
  // Bound the total before building anything: 10 axes x 10 values grew memory by ~190 MB/s
  // and 64 axes x 2 values overflowed the count to 0 (exit 0 having done nothing).
  std::size_t total = 0;
  for (const SweepSpec& sw : plan.sweeps) {
    std::size_t n = std::max<std::size_t>(plan.scenes.size(), 1) *
                    std::max<std::size_t>(plan.methods.size(), 1);
    std::string product = std::to_string(plan.scenes.size()) + " scenes x " +
                          std::to_string(plan.methods.size()) + " methods";
    for (const Axis& a : sw.axes) {
      product += " x " + std::to_string(a.values.size());
      if (a.values.size() > 0 && n > kMaxExperimentRuns / a.values.size())
        throw LimitError("'sweeps." + sw.name + ".axes': " + product +
                         " ... runs exceed the limit of " + std::to_string(kMaxExperimentRuns) +
                         " runs per experiment; split the sweep");
      n *= a.values.size();
    }
    total += n;
    if (total > kMaxExperimentRuns)
      throw LimitError("'sweeps': " + std::to_string(total) + " runs exceed the limit of " +
                       std::to_string(kMaxExperimentRuns) + " runs per experiment");
  }
  for (const SweepSpec& sw : plan.sweeps) {
    std::size_t points = 1;
    for (const Axis& a : sw.axes) points *= a.values.size();
    for (const auto& [mname, vals] : sw.paperFps.items())
      if (!vals.is_array() || vals.size() != points)
        throw ConfigError("'sweeps." + sw.name + ".paper_fps." + mname + "': expected " +
                          std::to_string(points) + " numbers (one per sweep point), got " +
                          describeValue(vals));
    for (const SceneSpec& sc : plan.scenes) {
      if (!sw.scenes.empty() &&
          std::find(sw.scenes.begin(), sw.scenes.end(), sc.name) == sw.scenes.end())
        continue;
      const std::string sceneHash = detail::sceneHash(sc.file);
      // A run whose overrides name a file (medium.density.file, objects.0.file, ...) hashes
      // the scene as they leave it.
      const auto namesFiles = [](const std::vector<std::string>& sets) {
        for (const std::string& a : sets) {
          const std::string path = a.substr(0, a.find('='));
          if (path.find("file") != std::string::npos || path.find("frames") != std::string::npos)
            return true;
        }
        return false;
      };
      for (std::size_t pt = 0; pt < points; ++pt) {
        std::vector<const AxisValue*> vals(sw.axes.size());
        std::size_t rest = pt;
        for (std::size_t k = sw.axes.size(); k-- > 0;) {
          vals[k] = &sw.axes[k].values[rest % sw.axes[k].values.size()];
          rest /= sw.axes[k].values.size();
        }
        for (const MethodSpec& m : plan.methods) {
          if (!sw.methods.empty() &&
              std::find(sw.methods.begin(), sw.methods.end(), m.name) == sw.methods.end())
            continue;
          RunSpec r = makeRun(plan, sw, sc, pt, vals, m, globalSets);
          if (!ids.insert(r.id).second)
            throw ConfigError("two runs get the id '" + r.id + "'; give methods distinct names");
          r.hash =
              runHash(plan, r, namesFiles(r.sets) ? detail::sceneHash(sc.file, r.sets) : sceneHash);
          plan.runs.push_back(std::move(r));
        }
      }
    }
  }
}

}  // namespace

Json ringOfLights(const Json& tmpl, const Vec3 c, int n) {
  Json out = Json::array();
  const auto rot = [](const Json& v, float phi) {
    const float x = v[0].get<float>(), y = v[1].get<float>(), z = v[2].get<float>();
    return Json{x * std::cos(phi) - z * std::sin(phi), y, x * std::sin(phi) + z * std::cos(phi)};
  };
  const auto scale = [n](const Json& v) {
    if (v.is_number()) return Json(v.get<double>() / n);
    Json o = Json::array();
    for (const Json& e : v) o.push_back(e.get<double>() / n);
    return o;
  };
  for (int i = 0; i < n; ++i) {
    const float phi = float(2.0 * M_PI * i / n);
    Json l = tmpl;
    if (l.contains("position") && l["position"].is_array() && l["position"].size() == 3) {
      const Json d = {l["position"][0].get<float>() - c.x, l["position"][1].get<float>() - c.y,
                      l["position"][2].get<float>() - c.z};
      const Json r = rot(d, phi);
      l["position"] = {c.x + r[0].get<float>(), c.y + r[1].get<float>(), c.z + r[2].get<float>()};
    }
    if (l.contains("direction") && l["direction"].is_array() && l["direction"].size() == 3)
      l["direction"] = rot(l["direction"], phi);
    if (l.contains("intensity")) l["intensity"] = scale(l["intensity"]);
    if (l.contains("irradiance")) l["irradiance"] = scale(l["irradiance"]);
    out.push_back(l);
  }
  return out;
}

Scene buildRunScene(const std::string& sceneFile, const std::vector<std::string>& sets,
                    std::optional<int> lights) {
  if (!lights) return loadScene(sceneFile, sets);
  Json doc = readJsonFile(sceneFile);
  for (const auto& o : sets) applyOverride(doc, o);
  const fs::path base = fs::path(sceneFile).parent_path();
  // Parse once for the medium box (the density type may supply it).
  Scene first;
  try {
    first = parseScene(doc, base);
  } catch (const ConfigError& e) {
    throw ConfigError(sceneFile + ": " + e.what());
  }
  if (!doc.contains("lights") || !doc["lights"].is_array() || doc["lights"].empty())
    throw ConfigError(sceneFile +
                      ": the 'lights' sweep axis needs at least one light to replicate");
  doc["lights"] = ringOfLights(doc["lights"][0], first.medium.bounds.center(), *lights);
  try {
    return parseScene(doc, base);
  } catch (const ConfigError& e) {
    throw ConfigError(sceneFile + ": " + e.what());
  }
}

ExperimentPlan parseExperiment(const std::string& configPath,
                               const std::vector<std::string>& overrides) {
  const Json cfg = readJsonFile(configPath);
  Params p(cfg, "");
  ExperimentPlan plan;
  plan.title = p.string("title", std::string("experiment"));
  plan.description = p.string("description", std::string());
  parseScenes(p, fs::path(configPath).parent_path(), plan);
  std::vector<std::string> globalSets = overrideList(p, "set");
  globalSets.insert(globalSets.end(), overrides.begin(), overrides.end());
  const std::string defBackend = p.choice("backend", {"cpu", "gpu", "auto"}, std::string("cpu"));
  plan.exposure = p.real("exposure", 0.0);
  if (p.has("mask_radius"))
    plan.maskRadius = p.number("mask_radius", std::nullopt, Interval::atLeast(0));
  else
    p.allow("mask_radius");
  plan.gallery = p.choice("gallery", {"images", "image+error", "off"}, std::string("images"));
  plan.htmlMaxSide = int(p.integer("html_max_side", 512, Interval::closed(16, 16384)));
  const int defReps = int(p.integer("repetitions", 3, Interval::closed(1, 1000)));
  const int defWarm = int(p.integer("warmup", 1, Interval::closed(0, 100)));
  const int defSteady = int(p.integer("steady_frames", 0, Interval::closed(0, 10000)));
  parseMethods(p, defBackend, plan);
  parseSweeps(p, plan, defReps, defWarm, defSteady);
  p.finish();
  expandRuns(plan, globalSets);
  return plan;
}

}  // namespace scatterlab
