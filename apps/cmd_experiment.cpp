#include <cstdio>

#include "api/scatterlab.h"
#include "apps/commands.h"
#include "experiment/experiment.h"

namespace scatterlab::cli {

Action addExperiment(CLI::App& app) {
  struct Opts {
    std::string config, out;
    std::vector<std::string> sets;
    bool quiet = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* c = app.add_subcommand(
      "experiment", "Run an experiment config: references + runs -> images, CSV, Markdown table");
  c->add_option("config", o->config, "Experiment config (JSON), e.g. data/experiments/fig3.json")
      ->required();
  c->add_option("-o,--output", o->out, "Output directory (created if missing)")->required();
  c->add_option("--set", o->sets, "Scene override applied to every render (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  c->add_flag("-q,--quiet", o->quiet, "No per-render log");
  return [o]() {
    runExperiment(o->config, o->out, o->sets, o->quiet ? nullptr : stderr);
    if (!o->quiet)
      std::printf("wrote %s/results.md, results.csv, results.json, side_by_side.png\n",
                  o->out.c_str());
    return 0;
  };
}

}  // namespace scatterlab::cli
