// The experiment's run loop: for each planned run, resume its record from DIR/runs/ or render
// it (warm-up, timed repetitions, peak host memory, images, errors against every reference),
// record failures and go on, with a progress bar and one log line per run.

#include <sys/resource.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>

#include "core/error.h"
#include "core/metrics.h"
#include "core/scene.h"
#include "experiment/detail.h"

namespace scatterlab::detail {

namespace fs = std::filesystem;

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

/// The process's heap for timing runs one after another (glibc): freed memory stays in the heap
/// (no block of its own per large allocation, no trimming), and each run starts by returning the
/// free memory to the system (startRun). Without this a run's time depended on what the runs
/// before it had left: glibc maps a large block afresh or takes it from the heap by a threshold
/// that moves with the sizes freed, and a fresh block costs its page faults (a 120³ scene's
/// per-voxel render 88 ms warm, 204 ms as the first of a process after its warm-up; the
/// population's cold/warm ratios 0.38–8.64, docs/fidelity.md "Times with and without a
/// warm-up, and the heap between runs"). So each run's warm-up pays the faults and its timed
/// repetitions reuse the memory, whatever ran before, and the memory measured from startRun is
/// the run's own.
void keepFreedMemory() {
#ifdef __GLIBC__
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
#endif
}

/// Returns the heap's free memory to the system before a run (glibc; see keepFreedMemory).
void startRun() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

/// A run's record before it is rendered: what it is and how it is configured.
RunRecord newRecord(const RunSpec& r, const ExperimentPlan& plan) {
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
  return rec;
}

class Runner {
 public:
  Runner(ExperimentResult& res, OutputDir& out, ReferenceCache& refs, const MemoryMeasure& mem,
         const ExperimentOptions& opt, bool progressBar, const std::vector<char>& selected,
         const Json& machine)
      : selected_(selected),
        machine_(machine),
        res_(res),
        plan_(res.plan),
        out_(out),
        refs_(refs),
        mem_(mem),
        opt_(opt),
        bar_{progressBar, int(std::count(selected.begin(), selected.end(), 1))} {}

  void runAll() {
    for (std::size_t i = 0; i < plan_.runs.size(); ++i) {
      if (!selected_[i]) continue;
      const RunSpec& r = plan_.runs[i];
      const std::string recordPath = out_.path("runs/" + r.id + ".json");
      if (opt_.recordsOnly) {
        takeRecord(r, recordPath);
        continue;
      }
      if (resume(r, recordPath)) continue;
      bar_.draw(r.id);
      const auto t0 = std::chrono::steady_clock::now();
      RunRecord rec = newRecord(r, plan_);
      rec.machine = machine_;
      try {
        render(r, rec);
        writeText(recordPath, rec.toJson().dump(2) + "\n");
        ++res_.rendered;
        logDone(r, rec);
      } catch (const UnsupportedSceneError& e) {
        refuse(rec, recordPath, e.what());
      } catch (const std::exception& e) {
        fail(rec, recordPath, e.what());
      }
      bar_.renderedSeconds +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      ++bar_.rendered;
      ++bar_.done;
      res_.runs.push_back(std::move(rec));
    }
    bar_.draw("done");
    bar_.finish();
  }

 private:
  /// A finished run with the same configuration hash is not rendered again: true when the
  /// record in DIR/runs/ was taken.
  bool resume(const RunSpec& r, const std::string& recordPath) {
    std::error_code ec;
    if (!fs::exists(fs::symlink_status(recordPath, ec))) return false;
    if (!fs::is_regular_file(recordPath, ec)) {
      // A FIFO there blocked the resume forever (issue 37), and a record written to it would
      // block too (outputs write through special files): not a record, removed and redone.
      out_.log(r.id + ": runs/" + r.id + ".json is not a regular file; removed, redoing it");
      fs::remove(recordPath, ec);
      return false;
    }
    try {
      RunRecord old = RunRecord::fromJson(readJsonFile(recordPath));
      if (old.hash == r.hash && (old.status == "ok" || old.status == "refused")) {
        // A refusal is the method's answer to the scene: kept, as a result is.
        old.resumed = true;
        const bool refused = old.status == "refused";
        res_.runs.push_back(std::move(old));
        ++(refused ? res_.refused : res_.resumed);
        ++bar_.done;
        bar_.draw(r.id + " (done before)");
        return true;
      }
      out_.log(r.id + ": record in runs/ has another configuration hash or failed; redoing it");
    } catch (const std::exception& e) {
      out_.log(r.id + ": unreadable record in runs/ (" + std::string(e.what()) + "); redoing it");
    }
    return false;
  }

  /// Merge mode: the record as the shard left it, failed or not (mergeShards has checked that
  /// it exists and that its hash is the plan's).
  void takeRecord(const RunSpec& r, const std::string& recordPath) {
    RunRecord old = RunRecord::fromJson(readJsonFile(recordPath));
    if (old.hash != r.hash)
      throw ConfigError("merge: '" + recordPath + "' was rendered with another configuration " +
                        "than the config now gives (hash " + old.hash + ", expected " + r.hash +
                        ")");
    old.resumed = true;
    if (old.status == "ok")
      ++res_.resumed;
    else if (old.status == "refused")
      ++res_.refused;
    else
      ++res_.failed;
    res_.runs.push_back(std::move(old));
  }

  /// Warm-up, then the timed repetitions; per-stage medians, memory, images and errors into
  /// `rec`. Throws on any failure, references included.
  void render(const RunSpec& r, RunRecord& rec) {
    const MethodSpec& m = *r.spec;
    const Scene scene = buildRunScene(r.sceneSpec->file, r.sets, r.lights);
    std::unique_ptr<Method> method = createMethod(scene, m.method, m.backend);
    const int reps = r.sweepSpec->repetitions, warm = r.sweepSpec->warmup;
    startRun();
    rec.baseHostMiB = procStatusMiB("VmRSS");
    resetPeakRss();
    for (int i = 0; i < warm; ++i) method->render(scene, nullptr);
    std::map<std::string, std::vector<double>> times;
    std::vector<std::string> order;
    std::vector<std::vector<std::pair<std::string, double>>> perRep;
    RenderResult last;
    for (int i = 0; i < reps; ++i) {
      last = method->render(scene, nullptr);
      perRep.push_back(last.stats.timingsMs);
      perRep.back().emplace_back("total", last.stats.totalMs());
      for (const auto& [s, ms] : last.stats.timingsMs) {
        if (!times.count(s)) order.push_back(s);
        times[s].push_back(ms);
      }
      times["total"].push_back(last.stats.totalMs());
    }
    rec.peakHostMiB = peakHostMiB();
    rec.memoryMethod = mem_.method;
    order.push_back("total");
    for (const std::string& s : order) rec.medianMs.emplace_back(s, median(times[s]));
    // The repetition whose total is nearest the median total (the first of ties).
    const double medTotal = rec.medianMs.back().second;
    std::size_t mid = 0;
    for (std::size_t i = 1; i < perRep.size(); ++i)
      if (std::abs(perRep[i].back().second - medTotal) <
          std::abs(perRep[mid].back().second - medTotal))
        mid = i;
    if (!perRep.empty()) rec.medianRunMs = perRep[mid];
    RenderStats st = last.stats;
    st.timingsMs.clear();
    for (const auto& [s, ms] : rec.medianMs)
      if (s != "total") st.timingsMs.emplace_back(s, ms);
    rec.stats = st.toJson();
    rec.samples = last.stats.samples;
    rec.repetitions = reps;
    rec.warmup = warm;
    if (r.sweepSpec->steadyFrames > 0) rec.steady = steadyFrames(r, m, scene);
    rec.image = "images/" + r.id + ".png";
    writeExr(last.image, out_.path("images/" + r.id + ".exr"));
    writePng(last.image, out_.path(rec.image), plan_.exposure);
    // The masked relative L2 needs the lights' projections: the run's own camera and lights.
    const LightMask mask = lightMask(scene, plan_.maskRadius.value_or(defaultMaskRadius(
                                                scene.camera.width, scene.camera.height)));
    for (const Light& l : scene.lights)
      if (l.type != Light::Type::Directional && scene.medium.bounds.contains(l.position))
        rec.lightInMedium = true;
    for (const MethodSpec& refSpec : plan_.references) {
      const bool same = r.axesAllAffectReference && !refSpec.converge &&
                        refSpec.method == m.method && refSpec.backend == m.backend &&
                        refSpec.sets == m.sets;
      Reference& ref = refs_.get(r, refSpec, same ? &last : nullptr);
      if (!ref.ok) throw Error("reference '" + refSpec.name + "' failed: " + ref.error);
      rec.referenceImages[refSpec.name] = ref.file;
      rec.errors.push_back(compareImages(last.image, ref.image, mask));
      if (!ref.check.is_null()) rec.referenceChecks[refSpec.name] = ref.check;
    }
    rec.status = "ok";
  }

  /// SweepSpec::steadyFrames frames of the run's method kept between renders after a first
  /// (cold) one, as a Renderer keeps it (Method::retainDensity, imageOnDevice): light 0 moved by
  /// 0.1 % of the box's width in a cycle of five positions (a directional light's direction
  /// tilted as much), density and samples kept, the image left on the device. Wall time per
  /// frame is the method's render (which returns once the frame's statistics are read: the
  /// GPU's work is inside it).
  Json steadyFrames(const RunSpec& r, const MethodSpec& m, const Scene& scene) {
    if (scene.lights.empty()) throw Error("steady frames need a light to move");
    std::unique_ptr<Method> method = createMethod(scene, m.method, m.backend);
    method->retainDensity = true;
    method->imageOnDevice = true;
    method->render(scene, nullptr);
    const Light& light = scene.lights[0];
    const bool directional = light.type == Light::Type::Directional;
    const float step = 1e-3f * (directional ? 1.0f : scene.medium.bounds.extent().x);
    std::vector<double> wall, gpu;
    double waits = 0;
    Scene moved = scene;  // shares the medium's density: the method sees it unchanged
    for (int f = 1; f <= r.sweepSpec->steadyFrames; ++f) {
      Light& l = moved.lights[0];
      if (directional)
        l.direction = glm::normalize(light.direction + Vec3(step * float(f % 5), 0.0f, 0.0f));
      else
        l.position = light.position + Vec3(step * float(f % 5), 0.0f, 0.0f);
      const auto t0 = std::chrono::steady_clock::now();
      const RenderResult res = method->render(moved, nullptr);
      wall.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      if (res.stats.extra.contains("gpu_ms_total"))
        gpu.push_back(res.stats.extra["gpu_ms_total"].get<double>());
      waits = std::max(waits, res.stats.extra.value("host_waits", 0.0));
    }
    Json j = {{"frames", r.sweepSpec->steadyFrames}, {"wall_ms", median(wall)}};
    if (!gpu.empty()) {
      j["gpu_ms"] = median(gpu);
      j["host_waits"] = waits;
    }
    return j;
  }

  double peakHostMiB() const {
    if (mem_.resettable) return procStatusMiB("VmHWM");
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    return double(ru.ru_maxrss) / 1024.0;
  }

  void logDone(const RunSpec& r, const RunRecord& rec) {
    std::string line = r.id + ": ok, median " + fmt(rec.totalMs(), "%.1f") + " ms over " +
                       std::to_string(rec.repetitions) + " (+" + std::to_string(rec.warmup) +
                       " warm-up)";
    if (!rec.errors.empty())
      line += ", rel L2 vs " + plan_.references[0].name + " " +
              fmt(100 * rec.errors[0].relL2, "%.2f") + "%, masked " +
              fmt(100 * rec.errors[0].maskedRelL2, "%.2f") + "% (" +
              fmt(rec.errors[0].maskRadius, "%.3g") + " px), visibly wrong " +
              fmt(100 * rec.errors[0].visiblyWrong, "%.3f") + "%";
    out_.log(line);
    if (opt_.log)
      std::fprintf(opt_.log, "%s%-40s %-10s %9.1f ms%s%s\n", bar_.enabled ? "\r\033[K" : "",
                   r.id.c_str(), rec.method.c_str(), rec.totalMs(),
                   rec.samples ? (", " + std::to_string(*rec.samples) + " samples").c_str() : "",
                   rec.errors.empty()
                       ? ""
                       : (", rel L2 " + fmt(100 * rec.errors[0].relL2, "%.2f") + "%").c_str());
  }

  /// Records the refusal (status "refused", the reason) and its record: the method cannot render
  /// the scene, which a resume keeps.
  void refuse(RunRecord& rec, const std::string& recordPath, const std::string& why) {
    rec.status = "refused";
    rec.error = why;
    rec.errors.clear();
    ++res_.refused;
    out_.log(rec.id + ": refused: " + rec.error);
    if (opt_.log)
      std::fprintf(opt_.log, "%s%s: refused: %s\n", bar_.enabled ? "\r\033[K" : "", rec.id.c_str(),
                   rec.error.c_str());
    writeText(recordPath, rec.toJson().dump(2) + "\n");
  }

  /// Records the failure (status, message, the run's config in log.txt) and its record, so
  /// that the sweep goes on and a resume retries the run.
  void fail(RunRecord& rec, const std::string& recordPath, const std::string& what) {
    rec.status = "failed";
    rec.error = what;
    rec.errors.clear();
    ++res_.failed;
    out_.log(rec.id + ": FAILED: " + rec.error + "; config: " + rec.config.dump());
    if (opt_.log)
      std::fprintf(opt_.log, "%s%s: FAILED: %s\n", bar_.enabled ? "\r\033[K" : "", rec.id.c_str(),
                   rec.error.c_str());
    try {
      writeText(recordPath, rec.toJson().dump(2) + "\n");
    } catch (const std::exception&) {
      // The failure is in the results and the log already; a missing record only means the
      // run is retried on resume, as a failed one would be.
    }
  }

  const std::vector<char>& selected_;
  const Json& machine_;
  ExperimentResult& res_;
  const ExperimentPlan& plan_;
  OutputDir& out_;
  ReferenceCache& refs_;
  const MemoryMeasure& mem_;
  const ExperimentOptions& opt_;
  SweepBar bar_;
};

}  // namespace

MemoryMeasure chooseMemoryMeasure() {
  MemoryMeasure m;
  m.resettable = resetPeakRss();
  m.method = m.resettable ? "VmHWM of the process after resetting it (clear_refs 5) before the run"
                          : "getrusage ru_maxrss (peak of the whole process so far)";
  return m;
}

void runAll(ExperimentResult& res, OutputDir& out, ReferenceCache& refs, const MemoryMeasure& mem,
            const ExperimentOptions& opt, bool progressBar, const std::vector<char>& selected,
            const Json& machine) {
  keepFreedMemory();
  Runner(res, out, refs, mem, opt, progressBar, selected, machine).runAll();
}

}  // namespace scatterlab::detail
