#include "experiment/experiment.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/scene.h"

#ifndef SCATTERLAB_SOURCE_DIR
#define SCATTERLAB_SOURCE_DIR "."
#endif

namespace scatterlab {

namespace fs = std::filesystem;

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

std::string fmt(double v, const char* f = "%.4g") {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

std::string readText(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

void writeText(const std::string& path, const std::string& text) {
  writeAtomically(path, [&](const std::string& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    f << text;
    f.close();
    if (!f) throw IoError("cannot write '" + path + "'");
  });
}

/// A method entry: a string (its name = the method) or an object.
MethodSpec parseMethod(const Json& j, const std::string& path, const std::string& defBackend) {
  MethodSpec m;
  if (j.is_string()) {
    m.name = m.method = j.get<std::string>();
    m.backend = defBackend;
  } else {
    Params r(j, path);
    m.method = r.string("method");
    m.name = r.string("name", m.method);
    m.backend = r.choice("backend", {"cpu", "gpu", "auto"}, defBackend);
    m.sets = stringList(r, "set");
    if (r.has("paper_rel_error"))
      m.paper["rel_error"] = r.number("paper_rel_error", std::nullopt, Interval::atLeast(0));
    else
      r.allow("paper_rel_error");
    if (r.has("paper_samples"))
      m.paper["samples"] = r.number("paper_samples", std::nullopt, Interval::atLeast(0));
    else
      r.allow("paper_samples");
    checkName(r, "name", m.name);
    r.finish();
  }
  if (!methods().contains(m.method)) {
    std::string list;
    for (const auto& n : methods().names()) list += (list.empty() ? "'" : ", '") + n + "'";
    throw ConfigError("'" + path + (j.is_string() ? "" : ".method") + "': unknown method '" +
                      m.method + "'; allowed: " + list);
  }
  if (!safeName(m.name))
    throw ConfigError("'" + path + "': method name '" + m.name + "' is not file-name safe");
  return m;
}

std::string valueLabel(const Json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_array()) {
    std::string s;
    for (const Json& e : v) s += (s.empty() ? "" : "x") + valueLabel(e);
    return s;
  }
  if (v.is_number_float()) {
    const double d = v.get<double>();
    if (d == std::floor(d) && std::fabs(d) < 1e15) return std::to_string((long long)d);
    return fmt(d, "%g");
  }
  return v.dump();
}

std::string fileSafe(std::string s) {
  for (char& c : s)
    if (!std::isalnum((unsigned char)c) && c != '-' && c != '_' && c != '.') c = '_';
  return s;
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
    throw ConfigError("'" + key + "': unknown sweep axis '" + name +
                      "'; allowed: resolution, samples, lights, image_size, epsilon, or a dotted "
                      "scene key such as render.sampler.radius_scale");
  Axis a;
  a.name = name;
  for (const Json& v : vals) {
    AxisValue av;
    av.value = v;
    const auto bad = [&](const std::string& what) {
      throw ConfigError("'" + key + "': bad value " + describeValue(v) + ": " + what);
    };
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
    a.values.push_back(std::move(av));
  }
  return a;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// "VmHWM" / "VmRSS" of this process in MiB (0 when unreadable).
double procStatusMiB(const char* field) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const std::string prefix = std::string(field) + ":";
  while (std::getline(f, line))
    if (line.rfind(prefix, 0) == 0) return std::atof(line.c_str() + prefix.size()) / 1024.0;
  return 0.0;
}

/// Resets the peak-RSS mark (Linux ≥ 4.0: writing 5 to clear_refs sets VmHWM to VmRSS).
bool resetPeakRss() {
  std::ofstream f("/proc/self/clear_refs");
  if (!f) return false;
  f << "5";
  f.close();
  return bool(f);
}

Json errorJson(const ImageError& e) {
  return {{"rel_l2", e.relL2},
          {"rel_l1", e.relL1},
          {"psnr", std::isfinite(e.psnr) ? Json(e.psnr) : Json(nullptr)},
          {"max_abs", e.maxAbs}};
}

/// A number from a record; `def` when missing or null (NaN and ±inf are written as null).
double num(const Json& j, const char* key, double def) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : def;
}

ImageError errorFromJson(const Json& j) {
  ImageError e;
  e.relL2 = num(j, "rel_l2", NAN);
  e.relL1 = num(j, "rel_l1", NAN);
  e.psnr = num(j, "psnr", INFINITY);
  e.maxAbs = num(j, "max_abs", NAN);
  return e;
}

/// Images side by side, left to right, with a 4-pixel black gap.
Image sideBySide(const std::vector<Image>& imgs) {
  int w = 0, h = 0;
  for (const Image& i : imgs) {
    w += i.width() + 4;
    h = std::max(h, i.height());
  }
  Image out(std::max(0, w - 4), h);
  int x0 = 0;
  for (const Image& i : imgs) {
    for (int y = 0; y < i.height(); ++y)
      for (int x = 0; x < i.width(); ++x) out.at(x0 + x, y) = i.at(x, y);
    x0 += i.width() + 4;
  }
  return out;
}

std::string nowIso() {
  const std::time_t t = std::time(nullptr);
  char b[64];
  std::strftime(b, sizeof b, "%Y-%m-%d %H:%M:%S", std::localtime(&t));
  return b;
}

}  // namespace

std::string findPlotPython() {
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("SCATTERLAB_PYTHON")) candidates.push_back(env);
  candidates.push_back("python3");
  candidates.push_back("/usr/bin/python3");
  for (const std::string& py : candidates) {
    const std::string cmd = "'" + py + "' -c 'import matplotlib' >/dev/null 2>&1";
    if (std::system(cmd.c_str()) == 0) return py;
  }
  return "";
}

// ---------------------------------------------------------------------------------------------
// Scenes with replicated lights

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
  const Json tmpl = doc["lights"][0];
  const Vec3 c = first.medium.bounds.center();
  const int n = *lights;
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
  doc["lights"] = out;
  try {
    return parseScene(doc, base);
  } catch (const ConfigError& e) {
    throw ConfigError(sceneFile + ": " + e.what());
  }
}

// ---------------------------------------------------------------------------------------------
// Config

ExperimentPlan parseExperiment(const std::string& configPath,
                               const std::vector<std::string>& overrides) {
  const Json cfg = readJsonFile(configPath);
  Params p(cfg, "");
  ExperimentPlan plan;
  plan.title = p.string("title", std::string("experiment"));
  plan.description = p.string("description", std::string());
  const fs::path base = fs::path(configPath).parent_path();
  const auto resolve = [&](const std::string& f) {
    return fs::path(f).is_absolute() ? f : (base / f).lexically_normal().string();
  };

  // Scenes.
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
      sc.sets = stringList(s, "set");
      s.finish();
      plan.scenes.push_back(sc);
    }
    if (plan.scenes.empty()) p.fail("scenes", "give at least one scene");
  }
  {
    std::set<std::string> seen;
    for (const SceneSpec& s : plan.scenes) {
      if (!seen.insert(s.name).second) p.fail("scenes", "two scenes are named '" + s.name + "'");
      checkReadableFile(s.file, "scene file");
    }
  }
  std::vector<std::string> globalSets = stringList(p, "set");
  globalSets.insert(globalSets.end(), overrides.begin(), overrides.end());
  const std::string defBackend = p.choice("backend", {"cpu", "gpu", "auto"}, std::string("cpu"));
  plan.exposure = p.real("exposure", 0.0);
  const int defReps = int(p.integer("repetitions", 3, Interval::closed(1, 1000)));
  const int defWarm = int(p.integer("warmup", 1, Interval::closed(0, 100)));

  // References and methods.
  {
    if (!p.has("references")) p.fail("references", "give at least one reference method");
    const Json& refs = p.raw("references");
    if (!refs.is_array() || refs.empty())
      p.fail("references", "expected a non-empty array of methods, got " + describeValue(refs));
    for (std::size_t i = 0; i < refs.size(); ++i)
      plan.references.push_back(
          parseMethod(refs[i], p.keyPath("references") + "[" + std::to_string(i) + "]", "cpu"));
  }
  const std::string methodsKey = p.has("runs") && !p.has("methods") ? "runs" : "methods";
  if (p.has("runs") && p.has("methods")) p.fail("runs", "give either 'methods' or 'runs'");
  p.allow(methodsKey == "runs" ? "methods" : "runs");
  {
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

  // Sweeps.
  if (p.has("sweeps")) {
    const Json& sw = p.raw("sweeps");
    if (!sw.is_array() || sw.empty())
      p.fail("sweeps", "expected a non-empty array of sweep objects, got " + describeValue(sw));
    std::set<std::string> seen;
    for (std::size_t i = 0; i < sw.size(); ++i) {
      Params s(sw[i], p.keyPath("sweeps") + "[" + std::to_string(i) + "]");
      SweepSpec sp;
      sp.name = s.string("name", "sweep" + std::to_string(i));
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
        if (std::none_of(plan.methods.begin(), plan.methods.end(),
                         [&](const MethodSpec& x) { return x.name == m; }))
          s.fail("methods", "'" + m + "' is not the name of an entry of 'methods'");
      sp.scenes = stringList(s, "scenes");
      for (const std::string& n : sp.scenes)
        if (std::none_of(plan.scenes.begin(), plan.scenes.end(),
                         [&](const SceneSpec& x) { return x.name == n; }))
          s.fail("scenes", "'" + n + "' is not the name of an entry of 'scenes'");
      sp.repetitions = int(s.integer("repetitions", defReps, Interval::closed(1, 1000)));
      sp.warmup = int(s.integer("warmup", defWarm, Interval::closed(0, 100)));
      sp.baseline = s.string("baseline", std::string());
      if (!sp.baseline.empty() &&
          std::none_of(plan.methods.begin(), plan.methods.end(),
                       [&](const MethodSpec& x) { return x.name == sp.baseline; }))
        s.fail("baseline", "'" + sp.baseline + "' is not the name of an entry of 'methods'");
      if (s.has("paper_fps")) {
        sp.paperFps = s.raw("paper_fps");
        if (!sp.paperFps.is_object()) s.fail("paper_fps", "expected {method name: [fps, ...]}");
      } else {
        s.allow("paper_fps");
      }
      s.finish();
      plan.sweeps.push_back(std::move(sp));
    }
  } else {
    p.allow("sweeps");
    SweepSpec sp;
    sp.name = "main";
    sp.repetitions = defReps;
    sp.warmup = defWarm;
    plan.sweeps.push_back(sp);
  }
  p.finish();

  // Expand: sweep × scene × point × method.
  const std::string sceneText = [&] {
    std::string t;
    for (const SceneSpec& s : plan.scenes) t += readText(s.file);
    return t;
  }();
  std::set<std::string> ids;
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
      const std::string sceneHash = stableHash(readText(sc.file));
      for (std::size_t pt = 0; pt < points; ++pt) {
        // Decode the point (last axis fastest).
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
          RunSpec r;
          r.sweep = sw.name;
          r.scene = sc.name;
          r.method = m.name;
          r.spec = &m;
          r.sceneSpec = &sc;
          r.sweepSpec = &sw;
          r.point = int(pt);
          // Order: scene's sets, global sets (+ --set), the run's method, the method's own sets,
          // then the sweep point. References get the same minus the method and the render.*
          // axes (sample budget, ε), so that one reference serves every budget.
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
          if (!ids.insert(id).second)
            throw ConfigError("two runs get the id '" + id + "'; give methods distinct names");
          r.paperFps = sw.paperFps.contains(m.name) ? sw.paperFps[m.name][pt] : Json(nullptr);
          Json key = {{"scene", sceneHash},
                      {"sets", r.sets},
                      {"backend", m.backend},
                      {"method", m.method},
                      {"repetitions", sw.repetitions},
                      {"warmup", sw.warmup},
                      {"lights", r.lights ? Json(*r.lights) : Json()}};
          Json refs = Json::array();
          for (const MethodSpec& ref : plan.references)
            refs.push_back({ref.method, ref.backend, ref.sets});
          key["references"] = refs;
          key["ref_sets"] = r.refSets;
          r.hash = stableHash(key.dump());
          plan.runs.push_back(std::move(r));
        }
      }
    }
  }
  (void)sceneText;
  return plan;
}

// ---------------------------------------------------------------------------------------------
// Records

double RunRecord::totalMs() const {
  for (const auto& [s, ms] : medianMs)
    if (s == "total") return ms;
  return 0.0;
}

Json RunRecord::toJson() const {
  Json j;
  j["id"] = id;
  j["sweep"] = sweep;
  j["scene"] = scene;
  j["method"] = methodName;
  j["registered_method"] = method;
  j["backend"] = backend;
  j["axes"] = axes;
  j["point"] = point;
  j["config_hash"] = hash;
  j["status"] = status;
  if (!error.empty()) j["error"] = error;
  j["stats"] = stats;
  Json t = Json::object();
  for (const auto& [s, ms] : medianMs) t[s] = ms;
  j["median_ms"] = t;
  j["repetitions"] = repetitions;
  j["warmup"] = warmup;
  Json e = Json::object();
  for (std::size_t k = 0; k < errors.size() && k < references.size(); ++k)
    e[references[k]] = errorJson(errors[k]);
  j["errors"] = e;
  j["references"] = references;
  j["peak_host_mib"] = peakHostMiB;
  j["base_host_mib"] = baseHostMiB;
  j["memory_method"] = memoryMethod;
  if (samples) j["samples"] = *samples;
  j["image"] = image;
  j["paper"] = paper;
  j["config"] = config;
  return j;
}

RunRecord RunRecord::fromJson(const Json& j) {
  RunRecord r;
  r.id = j.value("id", "");
  r.sweep = j.value("sweep", "");
  r.scene = j.value("scene", "");
  r.methodName = j.value("method", "");
  r.method = j.value("registered_method", "");
  r.backend = j.value("backend", "");
  r.axes = j.value("axes", Json::object());
  r.point = j.value("point", 0);
  r.hash = j.value("config_hash", "");
  r.status = j.value("status", "");
  r.error = j.value("error", "");
  r.stats = j.value("stats", Json::object());
  const Json median = j.value("median_ms", Json::object());  // a named copy: items() of a
  for (const auto& [s, ms] : median.items())                 // temporary dangles
    r.medianMs.emplace_back(s, ms.is_number() ? ms.get<double>() : NAN);
  r.repetitions = j.value("repetitions", 0);
  r.warmup = j.value("warmup", 0);
  r.references = j.value("references", std::vector<std::string>{});
  const Json e = j.value("errors", Json::object());
  for (const std::string& ref : r.references)
    r.errors.push_back(e.contains(ref) ? errorFromJson(e[ref]) : ImageError{});
  r.peakHostMiB = num(j, "peak_host_mib", 0.0);
  r.baseHostMiB = num(j, "base_host_mib", 0.0);
  r.memoryMethod = j.value("memory_method", "");
  if (j.contains("samples")) r.samples = j["samples"].get<long long>();
  r.image = j.value("image", "");
  r.paper = j.value("paper", Json::object());
  r.config = j.value("config", Json::object());
  return r;
}

// ---------------------------------------------------------------------------------------------
// Running

namespace {

struct SweepBar {
  bool enabled;
  int total, done = 0;
  double renderedSeconds = 0.0;
  int rendered = 0;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();

  void draw(const std::string& what) const {
    if (!enabled) return;
    const double el =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int left = total - done;
    const double eta = rendered > 0 ? renderedSeconds / rendered * left : 0.0;
    const int width = 24, filled = total ? done * width / total : width;
    std::fprintf(stderr, "\r\033[K[%.*s%*s] %d/%d runs, %.0fs elapsed, ETA %s  %s", filled,
                 "########################", width - filled, "", done, total, el,
                 rendered ? (fmt(eta, "%.0f") + "s").c_str() : "?", what.substr(0, 60).c_str());
    std::fflush(stderr);
  }
  void finish() const {
    if (enabled) std::fprintf(stderr, "\n");
  }
};

struct Reference {
  std::string name;
  Image image;
  bool ok = false;
  std::string error;
};

}  // namespace

ExperimentResult runExperiment(const std::string& configPath, const std::string& outDir,
                               const ExperimentOptions& opt) {
  ExperimentResult res;
  res.plan = parseExperiment(configPath, opt.overrides);
  const ExperimentPlan& plan = res.plan;
  fs::create_directories(fs::path(outDir) / "runs");
  fs::create_directories(fs::path(outDir) / "images");
  fs::create_directories(fs::path(outDir) / "references");
  const auto out = [&](const std::string& f) { return (fs::path(outDir) / f).string(); };
  std::ofstream logFile(out("log.txt"), std::ios::app);
  const auto logLine = [&](const std::string& s) {
    logFile << "[" << nowIso() << "] " << s << "\n";
    logFile.flush();
  };
  logLine("experiment '" + plan.title + "' from " + configPath + ": " +
          std::to_string(plan.runs.size()) + " runs");

  const bool peakResettable = resetPeakRss();
  const std::string memMethod =
      peakResettable ? "VmHWM of the process after resetting it (clear_refs 5) before the run"
                     : "getrusage ru_maxrss (peak of the whole process so far)";

  const bool barOn = opt.progress && ::isatty(STDERR_FILENO) != 0;
  // References, rendered once per distinct (scene, reference overrides, reference method) and
  // cached on disk under DIR/references/<name>-<hash>.exr.
  std::map<std::string, Reference> refCache;
  // `seed`: the image of a run that renders exactly the reference's configuration (same method,
  // backend, settings and scene), used instead of rendering it once more.
  const auto reference = [&](const RunSpec& r, const MethodSpec& ref,
                             const RenderResult* seed = nullptr) -> Reference& {
    const Json key = {{"scene", stableHash(readText(r.sceneSpec->file))},
                      {"sets", r.refSets},
                      {"lights", r.refLights ? Json(*r.refLights) : Json()},
                      {"method", ref.method},
                      {"backend", ref.backend},
                      {"ref_sets", ref.sets}};
    const std::string h = stableHash(key.dump());
    const std::string base = "references/" + ref.name + "-" + h;
    auto it = refCache.find(base);
    if (it != refCache.end()) return it->second;
    Reference& rc = refCache[base];
    rc.name = ref.name;
    try {
      if (fs::exists(out(base + ".exr")) && fs::exists(out(base + ".json"))) {
        rc.image = readExr(out(base + ".exr"));
        rc.ok = true;
        logLine("reference " + base + ": reused from disk");
      } else {
        std::vector<std::string> sets = r.refSets;
        sets.insert(sets.end(), ref.sets.begin(), ref.sets.end());
        RenderResult rr;
        if (seed) {
          rr = *seed;
        } else {
          const Scene scene = buildRunScene(r.sceneSpec->file, sets, r.refLights);
          rr = createMethod(scene, ref.method, ref.backend)->render(scene, nullptr);
        }
        writeExr(rr.image, out(base + ".exr"));
        writePng(rr.image, out(base + ".png"), plan.exposure);
        Json j = rr.stats.toJson();
        j["scene"] = r.sceneSpec->file;
        j["sets"] = sets;
        j["key"] = key;
        writeText(out(base + ".json"), j.dump(2) + "\n");
        rc.image = std::move(rr.image);
        rc.ok = true;
        logLine("reference " + base + (seed ? ": taken from run " + r.id : ": rendered") + " in " +
                fmt(rr.stats.totalMs(), "%.1f") + " ms");
        if (opt.log)
          std::fprintf(opt.log, "%sreference %-30s %9.1f ms\n", barOn ? "\r\033[K" : "",
                       ref.name.c_str(), rr.stats.totalMs());
      }
    } catch (const std::exception& e) {
      rc.error = e.what();
      logLine("reference " + base + " FAILED: " + rc.error);
    }
    return rc;
  };

  SweepBar bar{barOn, int(plan.runs.size())};
  for (const RunSpec& r : plan.runs) {
    const MethodSpec& m = *r.spec;
    RunRecord rec;
    rec.id = r.id;
    rec.sweep = r.sweep;
    rec.scene = r.scene;
    rec.method = m.method;
    rec.methodName = m.name;
    rec.backend = m.backend;
    rec.axes = r.axes;
    rec.point = r.point;
    rec.hash = r.hash;
    rec.paper = m.paper;
    if (!r.paperFps.is_null()) rec.paper["fps"] = r.paperFps;
    rec.config = {{"scene", r.sceneSpec->file},
                  {"sets", r.sets},
                  {"lights", r.lights ? Json(*r.lights) : Json()},
                  {"method", m.method},
                  {"backend", m.backend},
                  {"repetitions", r.sweepSpec->repetitions},
                  {"warmup", r.sweepSpec->warmup}};
    for (const MethodSpec& ref : plan.references) rec.references.push_back(ref.name);
    const std::string recordPath = out("runs/" + r.id + ".json");

    // Resume: a finished run with the same configuration hash is not rendered again.
    if (fs::exists(recordPath)) {
      try {
        RunRecord old = RunRecord::fromJson(readJsonFile(recordPath));
        if (old.hash == r.hash && old.status == "ok") {
          old.resumed = true;
          res.runs.push_back(std::move(old));
          ++res.resumed;
          ++bar.done;
          bar.draw(r.id + " (done before)");
          continue;
        }
        logLine(r.id + ": record in runs/ has another configuration hash or failed; redoing it");
      } catch (const std::exception& e) {
        logLine(r.id + ": unreadable record in runs/ (" + std::string(e.what()) + "); redoing it");
      }
    }
    bar.draw(r.id);
    const auto t0 = std::chrono::steady_clock::now();
    try {
      const Scene scene = buildRunScene(r.sceneSpec->file, r.sets, r.lights);
      std::unique_ptr<Method> method = createMethod(scene, m.method, m.backend);
      const int reps = r.sweepSpec->repetitions, warm = r.sweepSpec->warmup;
      rec.baseHostMiB = procStatusMiB("VmRSS");
      resetPeakRss();
      for (int i = 0; i < warm; ++i) method->render(scene, nullptr);
      std::map<std::string, std::vector<double>> times;
      std::vector<std::string> order;
      RenderResult last;
      for (int i = 0; i < reps; ++i) {
        last = method->render(scene, nullptr);
        for (const auto& [s, ms] : last.stats.timingsMs) {
          if (!times.count(s)) order.push_back(s);
          times[s].push_back(ms);
        }
        times["total"].push_back(last.stats.totalMs());
      }
      if (peakResettable) {
        rec.peakHostMiB = procStatusMiB("VmHWM");
      } else {
        rusage ru{};
        getrusage(RUSAGE_SELF, &ru);
        rec.peakHostMiB = double(ru.ru_maxrss) / 1024.0;
      }
      rec.memoryMethod = memMethod;
      order.push_back("total");
      for (const std::string& s : order) rec.medianMs.emplace_back(s, median(times[s]));
      RenderStats st = last.stats;
      st.timingsMs.clear();
      for (const auto& [s, ms] : rec.medianMs)
        if (s != "total") st.timingsMs.emplace_back(s, ms);
      rec.stats = st.toJson();
      rec.samples = last.stats.samples;
      rec.repetitions = reps;
      rec.warmup = warm;
      rec.image = "images/" + r.id + ".png";
      writeExr(last.image, out("images/" + r.id + ".exr"));
      writePng(last.image, out(rec.image), plan.exposure);
      for (const MethodSpec& refSpec : plan.references) {
        const bool same = r.axesAllAffectReference && refSpec.method == m.method &&
                          refSpec.backend == m.backend && refSpec.sets == m.sets;
        Reference& ref = reference(r, refSpec, same ? &last : nullptr);
        if (!ref.ok) throw Error("reference '" + refSpec.name + "' failed: " + ref.error);
        rec.errors.push_back(compareImages(last.image, ref.image));
      }
      rec.status = "ok";
      writeText(recordPath, rec.toJson().dump(2) + "\n");
      ++res.rendered;
      std::string line = r.id + ": ok, median " + fmt(rec.totalMs(), "%.1f") + " ms over " +
                         std::to_string(reps) + " (+" + std::to_string(warm) + " warm-up)";
      if (!rec.errors.empty())
        line += ", rel L2 vs " + plan.references[0].name + " " +
                fmt(100 * rec.errors[0].relL2, "%.2f") + "%";
      logLine(line);
      if (opt.log)
        std::fprintf(opt.log, "%s%-40s %-10s %9.1f ms%s%s\n", bar.enabled ? "\r\033[K" : "",
                     r.id.c_str(), m.method.c_str(), rec.totalMs(),
                     rec.samples ? (", " + std::to_string(*rec.samples) + " samples").c_str() : "",
                     rec.errors.empty()
                         ? ""
                         : (", rel L2 " + fmt(100 * rec.errors[0].relL2, "%.2f") + "%").c_str());
    } catch (const std::exception& e) {
      rec.status = "failed";
      rec.error = e.what();
      rec.errors.clear();
      ++res.failed;
      logLine(r.id + ": FAILED: " + rec.error + "; config: " + rec.config.dump());
      if (opt.log)
        std::fprintf(opt.log, "%s%s: FAILED: %s\n", bar.enabled ? "\r\033[K" : "", r.id.c_str(),
                     rec.error.c_str());
      try {
        writeText(recordPath, rec.toJson().dump(2) + "\n");
      } catch (const std::exception&) {
      }
    }
    bar.renderedSeconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ++bar.rendered;
    ++bar.done;
    res.runs.push_back(std::move(rec));
  }
  bar.draw("done");
  bar.finish();

  // ---- Tables ------------------------------------------------------------------------------
  std::vector<std::string> stages;  // union, in first-seen order
  std::vector<std::string> axisNames;
  for (const RunRecord& rec : res.runs) {
    for (const auto& [s, ms] : rec.medianMs)
      if (s != "total" && std::find(stages.begin(), stages.end(), s) == stages.end())
        stages.push_back(s);
    for (const auto& [a, v] : rec.axes.items())
      if (std::find(axisNames.begin(), axisNames.end(), a) == axisNames.end())
        axisNames.push_back(a);
  }
  const auto stageOf = [](const RunRecord& rec, const std::string& s) -> std::optional<double> {
    for (const auto& [n, ms] : rec.medianMs)
      if (n == s) return ms;
    return std::nullopt;
  };
  // Speed-up against the sweep's baseline at the same scene and point (same backend first).
  // Speed-up against the sweep's baseline at the same scene and point: the run of the
  // baseline's registered method on the same backend when there is one (per-voxel GPU for a GPU
  // run), else the baseline entry itself.
  const auto baselineOf = [&](const RunRecord& rec) -> const RunRecord* {
    const SweepSpec* sw = nullptr;
    for (const SweepSpec& s : plan.sweeps)
      if (s.name == rec.sweep) sw = &s;
    if (!sw || sw->baseline.empty()) return nullptr;
    std::string baseMethod;
    for (const MethodSpec& ms : plan.methods)
      if (ms.name == sw->baseline) baseMethod = ms.method;
    if (rec.method == baseMethod) return nullptr;
    const RunRecord *same = nullptr, *entry = nullptr;
    for (const RunRecord& o : res.runs) {
      if (o.sweep != rec.sweep || o.scene != rec.scene || o.point != rec.point || o.status != "ok")
        continue;
      if (o.methodName == sw->baseline) entry = &o;
      if (o.method == baseMethod && o.backend == rec.backend && !same) same = &o;
    }
    return same ? same : entry;
  };
  const auto dominant = [&](const RunRecord& rec) {
    std::string best;
    double bm = -1, total = rec.totalMs();
    for (const auto& [s, ms] : rec.medianMs)
      if (s != "total" && ms > bm) {
        bm = ms;
        best = s;
      }
    return best.empty() ? std::string()
                        : best + " (" + fmt(100 * bm / std::max(total, 1e-9), "%.0f") + "%)";
  };

  std::ostringstream csv;
  csv << "id,sweep,scene,method,registered_method,backend";
  for (const auto& a : axisNames) csv << ",axis_" << a;
  csv << ",status,samples,width,height,repetitions,total_ms,fps";
  for (const auto& s : stages) csv << "," << s << "_ms";
  for (const auto& r : plan.references)
    csv << ",rel_l2_vs_" << r.name << ",rel_l1_vs_" << r.name << ",psnr_vs_" << r.name;
  csv << ",speedup_vs_baseline,dominant_stage,peak_host_mib,paper_rel_error,paper_fps,paper_"
         "samples,resumed,error\n";
  Json jres;
  jres["title"] = plan.title;
  jres["config"] = fs::absolute(configPath).lexically_normal().string();
  jres["references"] = Json::array();
  for (const auto& r : plan.references) jres["references"].push_back(r.name);
  jres["axes"] = axisNames;
  jres["stages"] = stages;
  jres["runs"] = Json::array();
  jres["rendered"] = res.rendered;
  jres["resumed"] = res.resumed;
  jres["failed"] = res.failed;
  jres["memory_method"] = memMethod;
  const auto csvField = [](std::string s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string o = "\"";
    for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
    return o + "\"";
  };
  const auto paperStr = [](const Json& p, const char* k, const char* f) {
    return p.contains(k) && p[k].is_number() ? fmt(p[k].get<double>(), f) : std::string();
  };
  for (const RunRecord& rec : res.runs) {
    const bool ok = rec.status == "ok";
    csv << rec.id << "," << rec.sweep << "," << rec.scene << "," << rec.methodName << ","
        << rec.method << "," << rec.backend;
    for (const auto& a : axisNames)
      csv << "," << csvField(rec.axes.contains(a) ? valueLabel(rec.axes[a]) : "");
    csv << "," << rec.status << "," << (rec.samples ? std::to_string(*rec.samples) : "") << ","
        << (ok ? std::to_string(rec.stats.value("width", 0)) : "") << ","
        << (ok ? std::to_string(rec.stats.value("height", 0)) : "") << "," << rec.repetitions << ","
        << (ok ? fmt(rec.totalMs(), "%.2f") : "") << ","
        << (ok ? fmt(1000.0 / std::max(rec.totalMs(), 1e-9), "%.3f") : "");
    for (const auto& s : stages) {
      const auto v = stageOf(rec, s);
      csv << "," << (v ? fmt(*v, "%.2f") : "");
    }
    for (std::size_t k = 0; k < plan.references.size(); ++k) {
      if (ok && k < rec.errors.size())
        csv << "," << fmt(rec.errors[k].relL2, "%.6f") << "," << fmt(rec.errors[k].relL1, "%.6f")
            << "," << (std::isfinite(rec.errors[k].psnr) ? fmt(rec.errors[k].psnr, "%.2f") : "inf");
      else
        csv << ",,,";
    }
    const RunRecord* b = ok ? baselineOf(rec) : nullptr;
    // A plain double (valid when b): GCC 12 warns falsely about std::optional<double> here.
    const double speedup = b ? b->totalMs() / std::max(rec.totalMs(), 1e-9) : 0.0;
    csv << "," << (b ? fmt(speedup, "%.3f") : "") << "," << csvField(ok ? dominant(rec) : "") << ","
        << (ok ? fmt(rec.peakHostMiB, "%.1f") : "") << ","
        << paperStr(rec.paper, "rel_error", "%.4f") << "," << paperStr(rec.paper, "fps", "%.2f")
        << "," << paperStr(rec.paper, "samples", "%.0f") << "," << (rec.resumed ? 1 : 0) << ","
        << csvField(rec.error) << "\n";
    Json jr = rec.toJson();
    jr["resumed"] = rec.resumed;
    if (ok) jr["fps"] = 1000.0 / std::max(rec.totalMs(), 1e-9);
    if (b) {
      jr["speedup_vs_baseline"] = speedup;
      jr["baseline"] = b->methodName;
    }
    if (ok) jr["dominant_stage"] = dominant(rec);
    jres["runs"].push_back(jr);
  }

  // Report.
  std::ostringstream md;
  md << "# " << plan.title << "\n\n";
  if (!plan.description.empty()) md << plan.description << "\n\n";
  md << "Config `" << configPath << "`; " << res.runs.size() << " runs (" << res.rendered
     << " rendered now, " << res.resumed << " resumed from `runs/`, " << res.failed
     << " failed). Written " << nowIso() << ".\n\n"
     << "Times are medians over the stated repetitions after the warm-up, in ms per frame. "
        "Errors: relative L2 = sqrt(Σ(a−b)²)/sqrt(Σb²) over all pixels and channels (DESIGN.md "
        "§2), against the reference `"
     << plan.references[0].name << "`"
     << (plan.references.size() > 1 ? " (the other references are in results.csv)" : "")
     << ". Peak host memory: " << memMethod << ", MiB, whole process.\n\n";
  for (const SweepSpec& sw : plan.sweeps) {
    md << "## Sweep `" << sw.name << "`\n\n";
    md << "| run | scene | method | backend |";
    for (const Axis& a : sw.axes) md << " " << a.name << " |";
    md << " samples | time (ms) | fps |";
    if (!sw.paperFps.empty()) md << " paper fps |";
    if (!sw.baseline.empty()) md << " speed-up vs " << sw.baseline << " |";
    for (const auto& r : plan.references) md << " rel L2 vs " << r.name << " |";
    md << " paper rel. error | dominant stage | peak MiB |\n|---|---|---|---|";
    for (std::size_t k = 0; k < sw.axes.size(); ++k) md << "---|";
    md << "---|---|---|";
    if (!sw.paperFps.empty()) md << "---|";
    if (!sw.baseline.empty()) md << "---|";
    for (std::size_t k = 0; k < plan.references.size(); ++k) md << "---|";
    md << "---|---|---|\n";
    for (const RunRecord& rec : res.runs) {
      if (rec.sweep != sw.name) continue;
      const bool ok = rec.status == "ok";
      md << "| " << rec.id << " | " << rec.scene << " | " << rec.methodName << " | " << rec.backend
         << " |";
      for (const Axis& a : sw.axes)
        md << " " << (rec.axes.contains(a.name) ? valueLabel(rec.axes[a.name]) : "") << " |";
      if (!ok) {
        md << " **failed**: " << rec.error << " |\n";
        continue;
      }
      md << " " << (rec.samples ? std::to_string(*rec.samples) : "—") << " | "
         << fmt(rec.totalMs(), "%.1f") << " | "
         << fmt(1000.0 / std::max(rec.totalMs(), 1e-9), "%.2f") << " |";
      if (!sw.paperFps.empty()) md << " " << paperStr(rec.paper, "fps", "%.1f") << " |";
      if (!sw.baseline.empty()) {
        const RunRecord* b = baselineOf(rec);
        md << " " << (b ? fmt(b->totalMs() / std::max(rec.totalMs(), 1e-9), "%.2f") + "×" : "—")
           << " |";
      }
      for (std::size_t k = 0; k < plan.references.size(); ++k)
        md << " " << (k < rec.errors.size() ? fmt(100 * rec.errors[k].relL2, "%.2f") + "%" : "—")
           << " |";
      md << " "
         << (rec.paper.contains("rel_error")
                 ? fmt(100 * rec.paper["rel_error"].get<double>(), "%.1f") + "%"
                 : "—")
         << " | " << dominant(rec) << " | " << fmt(rec.peakHostMiB, "%.0f") << " |\n";
    }
    md << "\n";
    // Per-stage breakdown.
    md << "Per-stage medians (ms):\n\n| run |";
    for (const auto& s : stages) md << " " << s << " |";
    md << " total |\n|---|";
    for (std::size_t k = 0; k < stages.size(); ++k) md << "---|";
    md << "---|\n";
    for (const RunRecord& rec : res.runs) {
      if (rec.sweep != sw.name || rec.status != "ok") continue;
      md << "| " << rec.id << " |";
      for (const auto& s : stages) {
        const auto v = stageOf(rec, s);
        md << " " << (v ? fmt(*v, "%.1f") : "—") << " |";
      }
      md << " " << fmt(rec.totalMs(), "%.1f") << " |\n";
    }
    md << "\n";
  }

  // Gallery: one side-by-side image per (sweep, scene, point): references then the runs.
  md << "## Gallery\n\nEach strip: the reference(s), then the runs of that sweep point, left to "
        "right (PNG, exposure "
     << plan.exposure << ").\n\n";
  std::map<std::string, std::vector<const RunRecord*>> groups;
  std::vector<std::string> groupOrder;
  for (const RunRecord& rec : res.runs) {
    std::string g = rec.sweep + "__" + rec.scene;
    for (const auto& [a, v] : rec.axes.items())
      if (a != "samples" && a != "epsilon" && a.rfind("render.", 0) != 0)
        g += "__" + fileSafe(a) + "-" + fileSafe(valueLabel(v));
    if (!groups.count(g)) groupOrder.push_back(g);
    groups[g].push_back(&rec);
  }
  int strips = 0;
  for (const std::string& g : groupOrder) {
    std::vector<Image> imgs;
    std::vector<std::string> names;
    // The references of the group's first run, from the cache.
    const RunSpec* spec = nullptr;
    for (const RunSpec& r : plan.runs)
      if (r.id == groups[g].front()->id) spec = &r;
    try {
      if (spec)
        for (const MethodSpec& ref : plan.references) {
          Reference& rc = reference(*spec, ref);
          if (rc.ok) {
            imgs.push_back(rc.image);
            names.push_back(ref.name + " (reference)");
          }
        }
      for (const RunRecord* rec : groups[g])
        if (rec->status == "ok" && fs::exists(out("images/" + rec->id + ".exr"))) {
          imgs.push_back(readExr(out("images/" + rec->id + ".exr")));
          names.push_back(rec->methodName +
                          (rec->samples ? " (" + std::to_string(*rec->samples) + " samples)" : ""));
        }
      if (imgs.empty()) continue;
      // Keep strips a sensible size: at most 12 images.
      if (imgs.size() > 12) {
        imgs.resize(12);
        names.resize(12);
      }
      const std::string file =
          groupOrder.size() == 1 ? "side_by_side.png" : "gallery/" + g + ".png";
      if (groupOrder.size() > 1) fs::create_directories(out("gallery"));
      writePng(sideBySide(imgs), out(file), plan.exposure);
      std::string caption;
      for (const auto& n : names) caption += (caption.empty() ? "" : ", ") + n;
      md << "**" << g << "** — " << caption << "\n\n![" << g << "](" << file << ")\n\n";
      ++strips;
    } catch (const std::exception& e) {
      md << "**" << g << "** — gallery strip failed: " << e.what() << "\n\n";
    }
  }

  writeText(out("results.csv"), csv.str());
  writeText(out("results.json"), jres.dump(2) + "\n");

  // Plots.
  if (opt.plots) {
    const char* env = std::getenv("SCATTERLAB_PLOTS_SCRIPT");
    const std::string script =
        env ? env : (fs::path(SCATTERLAB_SOURCE_DIR) / "experiment" / "plots.py").string();
    if (!fs::exists(script)) {
      res.plotsNote = "plot script '" + script + "' not found";
    } else if (const std::string py = findPlotPython(); py.empty()) {
      res.plotsNote =
          "no python3 with matplotlib found ($SCATTERLAB_PYTHON, python3 on the PATH, "
          "/usr/bin/python3; install python3-matplotlib, e.g. by scripts/setup.sh)";
    } else {
      const std::string cmd =
          "'" + py + "' '" + script + "' '" + outDir + "' >> '" + out("log.txt") + "' 2>&1";
      if (std::system(cmd.c_str()) != 0) res.plotsNote = "the plot script failed; see log.txt";
    }
  } else {
    res.plotsNote = "plots not requested (--no-plots)";
  }
  md << "## Plots\n\n";
  if (!res.plotsNote.empty()) {
    md << "No plots: " << res.plotsNote << ".\n";
    logLine("plots: " + res.plotsNote);
  } else {
    std::vector<std::string> pngs;
    if (fs::exists(out("plots")))
      for (const auto& e : fs::directory_iterator(out("plots")))
        if (e.path().extension() == ".png") pngs.push_back(e.path().filename().string());
    std::sort(pngs.begin(), pngs.end());
    for (const auto& f : pngs) md << "![" << f << "](plots/" << f << ")\n\n";
    if (pngs.empty()) md << "No axis of this experiment has a plot.\n";
  }
  if (res.failed) {
    md << "\n## Failures\n\n";
    for (const RunRecord& rec : res.runs)
      if (rec.status != "ok")
        md << "- `" << rec.id << "`: " << rec.error << " — config `" << rec.config.dump() << "`\n";
  }
  writeText(out("report.md"), md.str());
  logLine("done: " + std::to_string(res.rendered) + " rendered, " + std::to_string(res.resumed) +
          " resumed, " + std::to_string(res.failed) + " failed");
  (void)strips;
  return res;
}

}  // namespace scatterlab
