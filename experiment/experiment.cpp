// runExperiment: the order in which the harness parses the config, renders (or resumes) the
// runs and writes the tables, the gallery, the plots and the report. The pieces are in plan.cpp,
// references.cpp, run.cpp, tables.cpp, report.cpp and gallery.cpp (shared helpers: detail.h).

#include "experiment/experiment.h"

#include <unistd.h>

#include <sstream>

#include "experiment/detail.h"

namespace scatterlab {

namespace {

/// Everything after the runs: plots.py reads results.json, so the tables are written before it
/// runs; the report lists the plots, so it is written last.
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
  detail::writeGallery(md, res.plan, res.runs, refs, out);
  detail::writeText(out.path("results.csv"), csv);
  detail::writeText(out.path("results.json"), json.dump(2) + "\n");
  res.plotsNote = detail::makePlots(opt, out);
  detail::reportPlots(md, res.plotsNote, out);
  detail::reportFailures(md, res);
  detail::writeText(out.path("report.md"), md.str());
  out.log("done: " + std::to_string(res.rendered) + " rendered, " + std::to_string(res.resumed) +
          " resumed, " + std::to_string(res.failed) + " failed");
}

}  // namespace

ExperimentResult runExperiment(const std::string& configPath, const std::string& outDir,
                               const ExperimentOptions& opt) {
  ExperimentResult res;
  res.plan = parseExperiment(configPath, opt.overrides);
  detail::OutputDir out(outDir);
  out.log("experiment '" + res.plan.title + "' from " + configPath + ": " +
          std::to_string(res.plan.runs.size()) + " runs");
  const detail::MemoryMeasure mem = detail::chooseMemoryMeasure();
  const bool progressBar = opt.progress && ::isatty(STDERR_FILENO) != 0;
  detail::ReferenceCache refs(res.plan, out, opt.log, progressBar);
  detail::runAll(res, out, refs, mem, opt, progressBar);
  writeOutputs(res, configPath, out, refs, mem.method, opt);
  return res;
}

}  // namespace scatterlab
