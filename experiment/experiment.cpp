// runExperiment: the order in which the harness parses the config, renders (or resumes) the
// runs and writes the tables, the gallery, the plots and the reports (report.md, report.html).
// The pieces are in plan.cpp, references.cpp, run.cpp, tables.cpp, report.cpp, report_html.cpp
// and gallery.cpp (shared helpers: detail.h).

#include "experiment/experiment.h"

#include <unistd.h>

#include <algorithm>
#include <sstream>

#include "core/error.h"

#include "experiment/detail.h"

namespace scatterlab {

namespace {

/// Everything after the runs: plots.py reads results.json, so the tables are written before it
/// runs; the report lists its plots and gallery pages, so it is written last.
void writeOutputs(ExperimentResult& res, const std::string& configPath, detail::OutputDir& out,
                  detail::ReferenceCache& refs, const std::string& memoryMethod,
                  const ExperimentOptions& opt) {
  const detail::ResultFacts facts(res.plan, res.runs);
  const std::string csv = detail::resultsCsv(facts);
  const Json json = detail::resultsJson(facts, res, configPath, memoryMethod);
  std::ostringstream md;
  detail::reportHeader(md, res, configPath, memoryMethod);
  for (const SweepSpec& sw : res.plan.sweeps) detail::reportSweep(md, facts, sw);
  detail::reportReferenceChecks(md, facts);
  detail::writeText(out.path("results.csv"), csv);
  detail::writeText(out.path("results.json"), json.dump(2) + "\n");
  res.plotsNote = detail::makePlots(opt, out);
  detail::writeGallery(md, res.plan, res.runs, refs, out, res.plotsNote.empty());
  detail::reportPlots(md, res.plotsNote, out);
  detail::reportFailures(md, res);
  detail::writeText(out.path("report.md"), md.str());
  detail::writeReportHtml(res, facts, configPath, memoryMethod, out);
  out.log("done: " + std::to_string(res.rendered) + " rendered, " + std::to_string(res.resumed) +
          " resumed, " + std::to_string(res.failed) + " failed, " + std::to_string(res.refused) +
          " refused");
}

}  // namespace

ExperimentResult runExperiment(const std::string& configPath, const std::string& outDir,
                               const ExperimentOptions& opt) {
  ExperimentResult res;
  res.machine = machineFacts();
  res.plan = parseExperiment(configPath, opt.overrides);
  const bool sharded = opt.shardCount > 0;
  if (sharded && (opt.shardIndex < 1 || opt.shardIndex > opt.shardCount))
    throw ConfigError("--shard " + std::to_string(opt.shardIndex) + "/" +
                      std::to_string(opt.shardCount) + ": K must be in 1..N");
  std::vector<char> selected(res.plan.runs.size(), 1);
  if (sharded) {
    const std::vector<int> owner = shardOf(res.plan, opt.shardCount);
    for (std::size_t i = 0; i < owner.size(); ++i) selected[i] = owner[i] == opt.shardIndex - 1;
  }
  detail::OutputDir out(outDir);
  out.log("experiment '" + res.plan.title + "' from " + configPath + ": " +
          std::to_string(res.plan.runs.size()) + " runs" +
          (sharded ? ", shard " + std::to_string(opt.shardIndex) + "/" +
                         std::to_string(opt.shardCount) + " of them: " +
                         std::to_string(std::count(selected.begin(), selected.end(), 1))
                   : std::string()) +
          (opt.recordsOnly ? " (merge: records only)" : "") + "; machine " + res.machine.dump());
  const detail::MemoryMeasure mem = detail::chooseMemoryMeasure();
  const bool progressBar = opt.progress && ::isatty(STDERR_FILENO) != 0;
  detail::ReferenceCache refs(res.plan, out, opt.log, progressBar);
  detail::runAll(res, out, refs, mem, opt, progressBar, selected, res.machine);
  if (sharded) {
    // The tables, report and plots need every run: `scatterlab experiment merge` writes them.
    detail::writeShardManifest(res, configPath, opt, selected, out);
    out.log("shard done: " + std::to_string(res.rendered) + " rendered, " +
            std::to_string(res.resumed) + " resumed, " + std::to_string(res.failed) + " failed, " +
            std::to_string(res.refused) + " refused");
    return res;
  }
  writeOutputs(res, configPath, out, refs, mem.method, opt);
  return res;
}

}  // namespace scatterlab
