// The experiment's report.md: title and conventions, per sweep a results table and a per-stage
// breakdown, the plots and the failures. (The gallery section is written by gallery.cpp.)

#include <algorithm>
#include <filesystem>

#include "experiment/detail.h"

namespace scatterlab::detail {

namespace fs = std::filesystem;

void reportHeader(std::ostream& md, const ExperimentResult& res, const std::string& configPath,
                  const std::string& memoryMethod) {
  const ExperimentPlan& plan = res.plan;
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
     << ". Peak host memory: " << memoryMethod << ", MiB, whole process.\n\n";
}

namespace {

void sweepTableHeader(std::ostream& md, const ExperimentPlan& plan, const SweepSpec& sw) {
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
}

void sweepTableRow(std::ostream& md, const ResultFacts& facts, const SweepSpec& sw,
                   const RunRecord& rec) {
  md << "| " << rec.id << " | " << rec.scene << " | " << rec.methodName << " | " << rec.backend
     << " |";
  for (const Axis& a : sw.axes)
    md << " " << (rec.axes.contains(a.name) ? valueLabel(rec.axes[a.name]) : "") << " |";
  if (rec.status != "ok") {
    md << " **failed**: " << rec.error << " |\n";
    return;
  }
  md << " " << (rec.samples ? std::to_string(*rec.samples) : "—") << " | "
     << fmt(rec.totalMs(), "%.1f") << " | " << fmt(1000.0 / std::max(rec.totalMs(), 1e-9), "%.2f")
     << " |";
  if (!sw.paperFps.empty()) md << " " << paperValue(rec.paper, "fps", "%.1f") << " |";
  if (!sw.baseline.empty()) {
    const RunRecord* b = facts.baselineOf(rec);
    md << " " << (b ? fmt(b->totalMs() / std::max(rec.totalMs(), 1e-9), "%.2f") + "×" : "—")
       << " |";
  }
  for (std::size_t k = 0; k < facts.plan.references.size(); ++k)
    md << " " << (k < rec.errors.size() ? fmt(100 * rec.errors[k].relL2, "%.2f") + "%" : "—")
       << " |";
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

void reportPlots(std::ostream& md, const std::string& plotsNote, OutputDir& out) {
  md << "## Plots\n\n";
  if (!plotsNote.empty()) {
    md << "No plots: " << plotsNote << ".\n";
    out.log("plots: " + plotsNote);
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
  if (!res.failed) return;
  md << "\n## Failures\n\n";
  for (const RunRecord& rec : res.runs)
    if (rec.status != "ok")
      md << "- `" << rec.id << "`: " << rec.error << " — config `" << rec.config.dump() << "`\n";
}

}  // namespace scatterlab::detail
