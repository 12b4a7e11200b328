// The experiment's tables: a run's record to and from JSON (DIR/runs/<id>.json), what the
// tables derive from the records (stages, speed-up against the baseline, dominant stage), and
// results.csv / results.json.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>

#include "experiment/detail.h"

namespace scatterlab {

namespace {

/// A finite number, else null (JSON has no NaN or infinity).
Json finite(double v) {
  return std::isfinite(v) ? Json(v) : Json(nullptr);
}

Json errorJson(const ImageError& e) {
  return {{"rel_l2", e.relL2},
          {"rel_l1", e.relL1},
          {"psnr", finite(e.psnr)},
          {"max_abs", e.maxAbs},
          {"visibly_wrong", e.visiblyWrong},
          {"masked_rel_l2", finite(e.maskedRelL2)},
          {"mask_radius_px", finite(e.maskRadius)},
          {"masked_lights", e.maskedLights}};
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
  e.visiblyWrong = num(j, "visibly_wrong", NAN);
  e.maskedRelL2 = num(j, "masked_rel_l2", NAN);
  e.maskRadius = num(j, "mask_radius_px", NAN);
  e.maskedLights = int(num(j, "masked_lights", 0));
  return e;
}

}  // namespace

double RunRecord::totalMs() const {
  for (const auto& [s, ms] : medianMs)
    if (s == "total") return ms;
  return 0.0;
}

std::string RunRecord::samplesLabel() const {
  if (stats.is_object() && stats.value("voxels_instead", false)) {
    const Json traced = stats.value("traced_voxels", Json());
    return "per-voxel: " + (traced.is_number() ? std::to_string(traced.get<long long>()) : "?") +
           " voxels";
  }
  return samples ? std::to_string(*samples) : "—";
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
  if (!medianRunMs.empty()) {
    Json m = Json::object();
    for (const auto& [s, ms] : medianRunMs) m[s] = ms;
    j["median_run_ms"] = m;
  }
  j["repetitions"] = repetitions;
  j["warmup"] = warmup;
  if (!steady.is_null()) j["steady"] = steady;
  Json e = Json::object();
  for (std::size_t k = 0; k < errors.size() && k < references.size(); ++k)
    e[references[k]] = errorJson(errors[k]);
  j["errors"] = e;
  j["references"] = references;
  j["reference_checks"] = referenceChecks;
  j["light_in_medium"] = lightInMedium;
  j["peak_host_mib"] = peakHostMiB;
  j["base_host_mib"] = baseHostMiB;
  j["memory_method"] = memoryMethod;
  if (samples) j["samples"] = *samples;
  j["image"] = image;
  j["reference_images"] = referenceImages;
  j["machine"] = machine;
  j["paper"] = paper;
  j["config"] = config;
  return j;
}

std::optional<double> RunRecord::steadyValue(const char* key) const {
  if (!steady.is_object() || !steady.contains(key) || !steady[key].is_number()) return {};
  return steady[key].get<double>();
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
  const Json medianRun = j.value("median_run_ms", Json::object());
  for (const auto& [s, ms] : medianRun.items())
    r.medianRunMs.emplace_back(s, ms.is_number() ? ms.get<double>() : NAN);
  r.repetitions = j.value("repetitions", 0);
  r.warmup = j.value("warmup", 0);
  r.steady = j.value("steady", Json());
  r.references = j.value("references", std::vector<std::string>{});
  const Json e = j.value("errors", Json::object());
  for (const std::string& ref : r.references)
    r.errors.push_back(e.contains(ref) ? errorFromJson(e[ref]) : ImageError{});
  r.referenceChecks = j.value("reference_checks", Json::object());
  r.lightInMedium = j.value("light_in_medium", false);
  r.peakHostMiB = num(j, "peak_host_mib", 0.0);
  r.baseHostMiB = num(j, "base_host_mib", 0.0);
  r.memoryMethod = j.value("memory_method", "");
  if (j.contains("samples")) r.samples = j["samples"].get<long long>();
  r.image = j.value("image", "");
  r.referenceImages = j.value("reference_images", Json::object());
  r.machine = j.value("machine", Json::object());
  r.paper = j.value("paper", Json::object());
  r.config = j.value("config", Json::object());
  return r;
}

namespace detail {

namespace fs = std::filesystem;

ResultFacts::ResultFacts(const ExperimentPlan& plan, const std::vector<RunRecord>& runs)
    : plan(plan), runs(runs) {
  for (const RunRecord& rec : runs) {
    for (const auto& [s, ms] : rec.medianMs)
      if (s != "total" && std::find(stages.begin(), stages.end(), s) == stages.end())
        stages.push_back(s);
    for (const auto& [a, v] : rec.axes.items())
      if (std::find(axisNames.begin(), axisNames.end(), a) == axisNames.end())
        axisNames.push_back(a);
    if (rec.status != "ok") continue;
    const Json& m = rec.machine;
    Json* found = nullptr;
    for (Json& k : machines)
      if (k.value("hostname", "") == m.value("hostname", "") &&
          k.value("cpu_model", "") == m.value("cpu_model", "") &&
          k.value("cores_used", 0) == m.value("cores_used", 0) &&
          k.value("commit", "") == m.value("commit", ""))
        found = &k;
    if (!found) {
      Json k = m;
      k["gpu_renderers"] = Json::array();
      k["runs"] = 0;
      machines.push_back(k);
      found = &machines.back();
    }
    (*found)["runs"] = (*found)["runs"].get<int>() + 1;
    const std::string device = rec.stats.value("device", "");
    if (rec.stats.value("backend", "") == "gpu" && !device.empty() &&
        std::find((*found)["gpu_renderers"].begin(), (*found)["gpu_renderers"].end(), device) ==
            (*found)["gpu_renderers"].end())
      (*found)["gpu_renderers"].push_back(device);
  }
}

std::optional<double> ResultFacts::stageMs(const RunRecord& rec, const std::string& stage) {
  for (const auto& [n, ms] : rec.medianMs)
    if (n == stage) return ms;
  return std::nullopt;
}

// Speed-up against the sweep's baseline at the same scene and point: the run of the baseline's
// registered method on the same backend when there is one (per-voxel GPU for a GPU run), else
// the baseline entry itself.
const RunRecord* ResultFacts::baselineOf(const RunRecord& rec) const {
  const SweepSpec* sw = nullptr;
  for (const SweepSpec& s : plan.sweeps)
    if (s.name == rec.sweep) sw = &s;
  if (!sw || sw->baseline.empty()) return nullptr;
  std::string baseMethod;
  for (const MethodSpec& ms : plan.methods)
    if (ms.name == sw->baseline) baseMethod = ms.method;
  if (rec.method == baseMethod) return nullptr;
  const RunRecord *same = nullptr, *entry = nullptr;
  for (const RunRecord& o : runs) {
    if (o.sweep != rec.sweep || o.scene != rec.scene || o.point != rec.point || o.status != "ok")
      continue;
    if (o.methodName == sw->baseline) entry = &o;
    if (o.method == baseMethod && o.backend == rec.backend && !same) same = &o;
  }
  return same ? same : entry;
}

std::string ResultFacts::dominantStage(const RunRecord& rec) {
  std::string best;
  double bm = -1, total = rec.totalMs();
  for (const auto& [s, ms] : rec.medianMs)
    if (s != "total" && ms > bm) {
      bm = ms;
      best = s;
    }
  return best.empty() ? std::string()
                      : best + " (" + fmt(100 * bm / std::max(total, 1e-9), "%.0f") + "%)";
}

std::string paperValue(const Json& p, const char* key, const char* format) {
  return p.contains(key) && p[key].is_number() ? fmt(p[key].get<double>(), format) : std::string();
}

namespace {

std::string csvField(std::string s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
  return o + "\"";
}

void csvHeader(std::ostream& csv, const ResultFacts& facts) {
  csv << "id,sweep,scene,method,registered_method,backend";
  for (const auto& a : facts.axisNames) csv << ",axis_" << a;
  csv << ",status,samples,width,height,repetitions,total_ms,fps,steady_frames,steady_wall_ms,"
         "steady_gpu_ms,steady_host_waits";
  for (const auto& s : facts.stages) csv << "," << s << "_ms";
  for (const auto& r : facts.plan.references)
    csv << ",rel_l2_vs_" << r.name << ",rel_l1_vs_" << r.name << ",psnr_vs_" << r.name
        << ",masked_rel_l2_vs_" << r.name << ",visibly_wrong_vs_" << r.name;
  csv << ",mask_radius_px";
  for (const auto& r : facts.plan.references)
    if (r.converge) csv << ",ref_step_voxels_" << r.name << ",ref_halving_change_" << r.name;
  csv << ",speedup_vs_baseline,dominant_stage,peak_host_mib,paper_rel_error,paper_fps,paper_"
         "samples,host,cpu_model,cores_used,load_avg_1min,commit,device,resumed,error\n";
}

void csvRow(std::ostream& csv, const ResultFacts& facts, const RunRecord& rec) {
  const bool ok = rec.status == "ok";
  csv << rec.id << "," << rec.sweep << "," << rec.scene << "," << rec.methodName << ","
      << rec.method << "," << rec.backend;
  for (const auto& a : facts.axisNames)
    csv << "," << csvField(rec.axes.contains(a) ? valueLabel(rec.axes[a]) : "");
  csv << "," << rec.status << "," << (rec.samples ? std::to_string(*rec.samples) : "") << ","
      << (ok ? std::to_string(rec.stats.value("width", 0)) : "") << ","
      << (ok ? std::to_string(rec.stats.value("height", 0)) : "") << "," << rec.repetitions << ","
      << (ok ? fmt(rec.totalMs(), "%.2f") : "") << ","
      << (ok ? fmt(1000.0 / std::max(rec.totalMs(), 1e-9), "%.3f") : "");
  const auto steady = [&](const char* key, const char* format) {
    const auto v = rec.steadyValue(key);
    return v ? fmt(*v, format) : std::string();
  };
  csv << "," << steady("frames", "%.0f") << "," << steady("wall_ms", "%.3f") << ","
      << steady("gpu_ms", "%.3f") << "," << steady("host_waits", "%.0f");
  for (const auto& s : facts.stages) {
    const auto v = ResultFacts::stageMs(rec, s);
    csv << "," << (v ? fmt(*v, "%.2f") : "");
  }
  const auto finiteOr = [](double v, const char* format, const char* otherwise) {
    return std::isfinite(v) ? fmt(v, format) : std::string(otherwise);
  };
  for (std::size_t k = 0; k < facts.plan.references.size(); ++k) {
    if (ok && k < rec.errors.size()) {
      const ImageError& e = rec.errors[k];
      csv << "," << fmt(e.relL2, "%.6f") << "," << fmt(e.relL1, "%.6f") << ","
          << finiteOr(e.psnr, "%.2f", "inf") << "," << finiteOr(e.maskedRelL2, "%.6f", "") << ","
          << finiteOr(e.visiblyWrong, "%.6f", "");
    } else {
      csv << ",,,,,";
    }
  }
  csv << "," << (ok && !rec.errors.empty() ? finiteOr(rec.errors[0].maskRadius, "%.3g", "") : "");
  for (const auto& r : facts.plan.references) {
    if (!r.converge) continue;
    const Json c = rec.referenceChecks.value(r.name, Json());
    if (c.is_object())
      csv << "," << fmt(c.value("step_voxels", NAN), "%.3g") << ","
          << fmt(c.value("change_rel_l2", NAN), "%.6f");
    else
      csv << ",,";
  }
  const RunRecord* b = ok ? facts.baselineOf(rec) : nullptr;
  // A plain double (valid when b): GCC 12 warns falsely about std::optional<double> here.
  const double speedup = b ? b->totalMs() / std::max(rec.totalMs(), 1e-9) : 0.0;
  csv << "," << (b ? fmt(speedup, "%.3f") : "") << ","
      << csvField(ok ? ResultFacts::dominantStage(rec) : "") << ","
      << (ok ? fmt(rec.peakHostMiB, "%.1f") : "") << ","
      << paperValue(rec.paper, "rel_error", "%.4f") << "," << paperValue(rec.paper, "fps", "%.2f")
      << "," << paperValue(rec.paper, "samples", "%.0f");
  // The machine (runs merged from several machines stay told apart) and the device it used.
  const Json m = rec.machine.is_object() ? rec.machine : Json::object();
  const Json load = m.value("load_avg_start", Json());
  csv << "," << csvField(m.value("hostname", "")) << "," << csvField(m.value("cpu_model", ""))
      << "," << (m.contains("cores_used") ? std::to_string(m["cores_used"].get<int>()) : "") << ","
      << (load.is_array() && !load.empty() ? fmt(load[0].get<double>(), "%.2f") : "") << ","
      << csvField(m.value("commit", "")) << ","
      << csvField(rec.stats.is_object() ? rec.stats.value("device", "") : "") << ","
      << (rec.resumed ? 1 : 0) << "," << csvField(rec.error) << "\n";
}

}  // namespace

Json referenceChecks(const ResultFacts& facts) {
  Json out = Json::array();
  std::set<std::string> seen;
  for (const RunRecord& rec : facts.runs)
    for (const auto& [ref, c] : rec.referenceChecks.items())
      if (seen.insert(c.value("file", ref + rec.id)).second) {
        Json e = c;
        e["reference"] = ref;
        e["scene"] = rec.scene;
        e["sweep"] = rec.sweep;
        e["first_run"] = rec.id;
        out.push_back(e);
      }
  return out;
}

std::string resultsCsv(const ResultFacts& facts) {
  std::ostringstream csv;
  csvHeader(csv, facts);
  for (const RunRecord& rec : facts.runs) csvRow(csv, facts, rec);
  return csv.str();
}

Json resultsJson(const ResultFacts& facts, const ExperimentResult& res,
                 const std::string& configPath, const std::string& memoryMethod) {
  const ExperimentPlan& plan = facts.plan;
  Json jres;
  jres["title"] = plan.title;
  jres["config"] = fs::absolute(configPath).lexically_normal().string();
  jres["references"] = Json::array();
  for (const auto& r : plan.references) jres["references"].push_back(r.name);
  jres["axes"] = facts.axisNames;
  jres["stages"] = facts.stages;
  jres["runs"] = Json::array();
  jres["rendered"] = res.rendered;
  jres["resumed"] = res.resumed;
  jres["failed"] = res.failed;
  jres["refused"] = res.refused;
  jres["memory_method"] = memoryMethod;
  jres["default_reference"] = plan.defaultReference;
  jres["reference_checks"] = referenceChecks(facts);
  jres["machine"] = res.machine;
  jres["gallery"] = plan.gallery;  // plots.py makes no gallery pages for "off"

  jres["machines"] = facts.machines;
  for (const RunRecord& rec : facts.runs) {
    const bool ok = rec.status == "ok";
    const RunRecord* b = ok ? facts.baselineOf(rec) : nullptr;
    Json jr = rec.toJson();
    jr["resumed"] = rec.resumed;
    if (ok) jr["fps"] = 1000.0 / std::max(rec.totalMs(), 1e-9);
    if (b) {
      jr["speedup_vs_baseline"] = b->totalMs() / std::max(rec.totalMs(), 1e-9);
      jr["baseline"] = b->methodName;
    }
    if (ok) jr["dominant_stage"] = ResultFacts::dominantStage(rec);
    jres["runs"].push_back(jr);
  }
  return jres;
}

}  // namespace detail

}  // namespace scatterlab
