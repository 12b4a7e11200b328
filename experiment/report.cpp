// The experiment's report.md: title and conventions, per sweep a results table and a per-stage
// breakdown, the plots and the failures. (The gallery section is written by gallery.cpp.)

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include "core/scene.h"
#include "experiment/detail.h"

namespace scatterlab::detail {

namespace fs = std::filesystem;

std::string machineLine(const Json& m) {
  if (!m.contains("cpu_model"))
    return "unknown (" + std::to_string(m.value("runs", 0)) +
           " runs from records written before machine facts)";
  std::string s = m.value("cpu_model", "?") + ", " + std::to_string(m.value("cores_used", 0)) +
                  " of " + std::to_string(m.value("logical_cpus", 0)) + " logical CPUs used";
  const Json la = m.value("load_avg_start", Json());
  if (la.is_array() && la.size() == 3)
    s += ", load average " + fmt(la[0].get<double>(), "%.2f") + " / " +
         fmt(la[1].get<double>(), "%.2f") + " / " + fmt(la[2].get<double>(), "%.2f") +
         " (1/5/15 min) at the start";
  std::string gpus;
  for (const Json& g : m.value("gpu_renderers", Json::array()))
    gpus += (gpus.empty() ? "" : ", ") + g.get<std::string>();
  s += "; GPU: " + (gpus.empty() ? std::string("not used") : gpus);
  s += "; host `" + m.value("hostname", "?") + "`, " + m.value("os", "?") + ", commit `" +
       m.value("commit", "?") + "`";
  if (m.contains("runs")) s += " (" + std::to_string(m["runs"].get<int>()) + " runs)";
  return s;
}

namespace {

/// `text` with HTML's special characters as entities: Markdown passes raw HTML through, and a
/// config's title or description must read as text (issue 37; report.html escapes them too).
std::string markdownText(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '&')
      out += "&amp;";
    else
      out += c;
  }
  return out;
}

}  // namespace

void reportHeader(std::ostream& md, const ExperimentResult& res, const std::string& configPath,
                  const std::string& memoryMethod) {
  const ExperimentPlan& plan = res.plan;
  md << "# " << markdownText(plan.title) << "\n\n";
  if (!plan.description.empty()) md << markdownText(plan.description) << "\n\n";
  md << "Config `" << configPath << "`; " << res.runs.size() << " runs (" << res.rendered
     << " rendered now, " << res.resumed << " resumed from `runs/`, " << res.failed << " failed, "
     << res.refused << " refused). Written " << nowIso() << ".\n\n"
     << "Times are medians over the stated repetitions after the warm-up, in ms per frame "
        "(cold frames: a new method per render); the steady columns, where a sweep has "
        "steady_frames, are medians over that many frames of one method kept between renders, "
        "light 0 moved, the image left on the device (what an engine draws). "
        "Errors (docs/metrics.md), against the reference `"
     << plan.references[0].name << "`"
     << (plan.references.size() > 1 ? " (against the others: rel L2 here, the rest in results.csv)"
                                    : "")
     << ": relative L2 = sqrt(Σ(a−b)²)/sqrt(Σb²) over all pixels and channels (the headline); "
        "masked rel L2 = the same without the pixels within K px of each point or spot light's "
        "projection (K in the column; a 1/d² glow puts nearly all squared error in those "
        "pixels); relative L1 = Σ|a−b|/Σ|b|; visibly wrong = share of pixels where some channel "
        "of the PNG transform (exposure 0, clamp, sRGB) differs by more than "
     << kVisibleThreshold << ". Peak host memory: " << memoryMethod << ", MiB, whole process.\n\n";
  const ResultFacts facts(plan, res.runs);
  if (facts.machines.size() > 1)
    md << "**These runs come from " << facts.machines.size()
       << " different machines or commits** (below): compare times only between runs of one "
          "machine.\n\n";
  for (const Json& m : facts.machines) md << "Machine: " << machineLine(m) << ".\n\n";
  if (plan.defaultReference)
    md << "Reference: the default, `exact` with march_step = delta1 = ½ voxel, checked by "
          "halving both once more (see *Reference convergence*).\n\n";
  // per-voxel interpolates S trilinearly from voxel centres: close to exact far from the lights
  // (0.03 % on Fig. 3's plume), but next to a light inside the medium it blurs the 1/d² peak.
  // A reference other than exact is therefore called a baseline wherever a light is inside the
  // medium's box, and exact (when the experiment has it) the reference.
  std::set<std::string> inMedium;
  for (const RunRecord& rec : res.runs)
    if (rec.lightInMedium) inMedium.insert(rec.scene);
  bool hasExact = false;
  for (const MethodSpec& ref : plan.references) hasExact = hasExact || ref.method == "exact";
  for (const MethodSpec& ref : plan.references)
    if (ref.method != "exact" && !inMedium.empty()) {
      std::string list;
      for (const std::string& s : inMedium) list += (list.empty() ? "`" : ", `") + s + "`";
      md << "**`" << ref.name << "` is a baseline, not the reference, on " << list
         << "**: a point or spot light sits inside the medium's box there (a conservative test: "
            "the density around the light is not looked at), and a method that interpolates S "
            "from a volume can blur the 1/d² peak next to it; errors against `"
         << ref.name << "` are differences from that baseline (the paper's reference). "
         << (hasExact ? "`exact` is the reference: judge accuracy against it."
                      : "Add `exact` to `references` to judge accuracy.")
         << "\n\n";
    }
}

namespace {

void sweepTableHeader(std::ostream& md, const ExperimentPlan& plan, const SweepSpec& sw) {
  md << "| run | scene | method | backend |";
  // A `samples` axis is the budget asked for; the count column is what the method used
  // (adaptive splits beyond its budget's initial set).
  for (const Axis& a : sw.axes)
    md << " " << (a.name == "samples" ? "sample budget" : a.name) << " |";
  md << " samples used | time (ms) | fps |";
  // Steady frames (SweepSpec::steadyFrames): the cold columns above, these beside them.
  if (sw.steadyFrames > 0) md << " steady wall ms | steady GPU ms | steady host waits |";
  if (!sw.paperFps.empty()) md << " paper fps |";
  if (!sw.baseline.empty()) md << " speed-up vs " << sw.baseline << " |";
  const std::string& head = plan.references[0].name;
  md << " rel L2 vs " << head << " | masked rel L2 (K px) | rel L1 | visibly wrong |";
  for (std::size_t k = 1; k < plan.references.size(); ++k)
    md << " rel L2 vs " << plan.references[k].name << " |";
  md << " paper rel. error | dominant stage | peak MiB |\n|---|---|---|---|";
  for (std::size_t k = 0; k < sw.axes.size(); ++k) md << "---|";
  md << "---|---|---|";
  if (sw.steadyFrames > 0) md << "---|---|---|";
  if (!sw.paperFps.empty()) md << "---|";
  if (!sw.baseline.empty()) md << "---|";
  md << "---|---|---|";
  for (std::size_t k = 0; k < plan.references.size(); ++k) md << "---|";
  md << "---|---|---|\n";
}

void sweepTableRow(std::ostream& md, const ResultFacts& facts, const SweepSpec& sw,
                   const RunRecord& rec) {
  md << "| " << rec.id << " | " << rec.scene << " | " << rec.methodName << " | " << rec.backend
     << " |";
  for (const Axis& a : sw.axes)
    md << " " << (rec.axes.contains(a.name) ? valueLabel(rec.axes[a.name]) : "") << " |";
  if (rec.status != "ok") {
    md << " **" << (rec.status == "refused" ? "refused" : "failed") << "**: " << rec.error
       << " |\n";
    return;
  }
  md << " " << rec.samplesLabel() << " | " << fmt(rec.totalMs(), "%.1f") << " | "
     << fmt(1000.0 / std::max(rec.totalMs(), 1e-9), "%.2f") << " |";
  if (sw.steadyFrames > 0) {
    const auto steady = [&](const char* key, const char* format) {
      const auto v = rec.steadyValue(key);
      return v ? fmt(*v, format) : std::string("—");
    };
    md << " " << steady("wall_ms", "%.2f") << " | " << steady("gpu_ms", "%.2f") << " | "
       << steady("host_waits", "%.0f") << " |";
  }
  if (!sw.paperFps.empty()) md << " " << paperValue(rec.paper, "fps", "%.1f") << " |";
  if (!sw.baseline.empty()) {
    const RunRecord* b = facts.baselineOf(rec);
    md << " " << (b ? fmt(b->totalMs() / std::max(rec.totalMs(), 1e-9), "%.2f") + "×" : "—")
       << " |";
  }
  if (!rec.errors.empty()) {
    const ImageError& e = rec.errors[0];
    md << " " << percent(e.relL2, "%.2f") << " | " << percent(e.maskedRelL2, "%.2f")
       << (std::isfinite(e.maskRadius) ? " (" + fmt(e.maskRadius, "%.3g") + ")" : "") << " | "
       << percent(e.relL1, "%.2f") << " | " << percent(e.visiblyWrong, "%.3f") << " |";
  } else {
    md << " — | — | — | — |";
  }
  for (std::size_t k = 1; k < facts.plan.references.size(); ++k)
    md << " " << (k < rec.errors.size() ? percent(rec.errors[k].relL2, "%.2f") : "—") << " |";
  md << " "
     << (rec.paper.contains("rel_error")
             ? fmt(100 * rec.paper["rel_error"].get<double>(), "%.1f") + "%"
             : "—")
     << " | " << ResultFacts::dominantStage(rec) << " | " << fmt(rec.peakHostMiB, "%.0f") << " |\n";
}

void stageTable(std::ostream& md, const ResultFacts& facts, const SweepSpec& sw) {
  md << "Per-stage medians (ms):\n\n| run |";
  for (const auto& s : facts.stages) md << " " << s << " |";
  md << " total |\n|---|";
  for (std::size_t k = 0; k < facts.stages.size(); ++k) md << "---|";
  md << "---|\n";
  for (const RunRecord& rec : facts.runs) {
    if (rec.sweep != sw.name || rec.status != "ok") continue;
    md << "| " << rec.id << " |";
    for (const auto& s : facts.stages) {
      const auto v = ResultFacts::stageMs(rec, s);
      md << " " << (v ? fmt(*v, "%.1f") : "—") << " |";
    }
    md << " " << fmt(rec.totalMs(), "%.1f") << " |\n";
  }
  md << "\n";
}

}  // namespace

void reportSweep(std::ostream& md, const ResultFacts& facts, const SweepSpec& sweep) {
  md << "## Sweep `" << sweep.name << "`\n\n";
  sweepTableHeader(md, facts.plan, sweep);
  for (const RunRecord& rec : facts.runs)
    if (rec.sweep == sweep.name) sweepTableRow(md, facts, sweep, rec);
  md << "\n";
  stageTable(md, facts, sweep);
}

void reportReferenceChecks(std::ostream& md, const ResultFacts& facts) {
  const Json checks = referenceChecks(facts);
  if (checks.empty()) return;
  md << "## Reference convergence\n\nEach converged reference is rendered with march_step = "
        "delta1 = ½ voxel and again with both halved; when the two differ by "
     << fmt(100 * kReferenceTolerance, "%.2g")
     << "% relative L2 or more, the finer image becomes the reference (refined once; its own "
        "change is not measured).\n\n| reference | scene | first run | voxel | step used | "
        "change on halving | verdict |\n|---|---|---|---|---|---|---|\n";
  for (const Json& c : checks)
    md << "| " << c.value("reference", "") << " | " << c.value("scene", "") << " | "
       << c.value("first_run", "") << " | " << fmt(c.value("voxel", NAN), "%.4g") << " | "
       << fmt(c.value("step", NAN), "%.4g") << " (" << fmt(c.value("step_voxels", NAN), "%.3g")
       << " voxel) | " << fmt(100 * c.value("change_rel_l2", NAN), "%.3f") << "% | "
       << (c.value("passed", false) ? "converged (< " : "**refined** (≥ ")
       << fmt(100 * c.value("threshold", NAN), "%.2g") << "%) |\n";
  md << "\n";
}

void reportPlots(std::ostream& md, const std::string& plotsNote, OutputDir& out) {
  md << "## Plots\n\n";
  if (!plotsNote.empty()) {
    md << "No plots: " << plotsNote << ".\n";
    out.log("plots: " + plotsNote);
    return;
  }
  if (fs::exists(out.path("plots/index.json"))) {
    const Json index = readJsonFile(out.path("plots/index.json"));
    for (const Json& p : index)
      md << p.value("caption", "") << " ([SVG](plots/" << p.value("svg", "") << ")):\n\n!["
         << p.value("file", "") << "](plots/" << p.value("file", "") << ")\n\n";
    if (index.empty()) md << "No sweep of this experiment has data for a plot.\n";
    return;
  }
  std::vector<std::string> pngs;
  if (fs::exists(out.path("plots")))
    for (const auto& e : fs::directory_iterator(out.path("plots")))
      if (e.path().extension() == ".png") pngs.push_back(e.path().filename().string());
  std::sort(pngs.begin(), pngs.end());
  for (const auto& f : pngs) md << "![" << f << "](plots/" << f << ")\n\n";
  if (pngs.empty()) md << "No axis of this experiment has a plot.\n";
}

void reportFailures(std::ostream& md, const ExperimentResult& res) {
  if (res.refused) {
    md << "\n## Refused\n\nRuns whose method cannot render their scene (not failures):\n\n";
    for (const RunRecord& rec : res.runs)
      if (rec.status == "refused") md << "- `" << rec.id << "`: " << rec.error << "\n";
  }
  if (!res.failed) return;
  md << "\n## Failures\n\n";
  for (const RunRecord& rec : res.runs)
    if (rec.status == "failed")
      md << "- `" << rec.id << "`: " << rec.error << " — config `" << rec.config.dump() << "`\n";
}

}  // namespace scatterlab::detail
