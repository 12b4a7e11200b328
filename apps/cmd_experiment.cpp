#include <cstdio>

#include "api/scatterlab.h"
#include "apps/commands.h"
#include "experiment/experiment.h"

namespace scatterlab::cli {

Action addExperiment(CLI::App& app) {
  struct Opts {
    std::string config, out;
    std::vector<std::string> sets;
    bool quiet = false, noPlots = false, noProgress = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* c = app.add_subcommand(
      "experiment",
      "Run an experiment config (scenes x methods x sweeps, docs/harness.md): images, "
      "results.csv, results.json, report.md, plots; resumes an interrupted sweep");
  c->add_option("config", o->config, "Experiment config (JSON), e.g. data/experiments/fig3.json")
      ->required();
  c->add_option("-o,--output", o->out, "Output directory (created if missing; reused to resume)")
      ->required();
  c->add_option("--set", o->sets, "Scene override applied to every render (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  c->add_flag("-q,--quiet", o->quiet, "No per-run log on stderr (DIR/log.txt is still written)");
  c->add_flag("--no-plots", o->noPlots, "Do not call experiment/plots.py");
  c->add_flag("--no-progress", o->noProgress, "No progress bar");
  return [o]() {
    ExperimentOptions opt;
    opt.overrides = o->sets;
    opt.log = o->quiet ? nullptr : stderr;
    opt.progress = !o->noProgress;
    opt.plots = !o->noPlots;
    const ExperimentResult r = runExperiment(o->config, o->out, opt);
    if (!r.plotsNote.empty()) std::fprintf(stderr, "note: %s\n", r.plotsNote.c_str());
    std::printf("%zu runs: %d rendered, %d resumed, %d failed; wrote %s/report.md, results.csv, "
                "results.json, images/, log.txt%s\n",
                r.runs.size(), r.rendered, r.resumed, r.failed, o->out.c_str(),
                r.plotsNote.empty() ? ", plots/" : "");
    if (r.failed) {
      std::fprintf(stderr, "error: %d run(s) failed; see %s/log.txt\n", r.failed, o->out.c_str());
      return 1;
    }
    return 0;
  };
}

}  // namespace scatterlab::cli
