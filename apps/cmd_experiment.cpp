#include <algorithm>
#include <cstdio>

#include "api/scatterlab.h"
#include "apps/commands.h"
#include "experiment/experiment.h"

namespace scatterlab::cli {

namespace {

/// "K/N" with 1 <= K <= N into (K, N); "" when it is, else why not (CLI11 validator form).
std::string parseShard(const std::string& s, int* k = nullptr, int* n = nullptr) {
  int a = 0, b = 0;
  char slash = 0, extra = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &a, &slash, &b, &extra) != 3 || slash != '/' || b < 1 ||
      a < 1 || a > b)
    return "'" + s + "': expected K/N with 1 <= K <= N, e.g. 2/4";
  if (k) *k = a;
  if (n) *n = b;
  return "";
}

int printSummary(const ExperimentResult& r, const std::string& out, bool shard) {
  if (!r.plotsNote.empty() && !shard) std::fprintf(stderr, "note: %s\n", r.plotsNote.c_str());
  if (shard)
    std::printf(
        "%zu runs of this shard: %d rendered, %d resumed, %d failed, %d refused; wrote %s/runs/, "
        "images/, references/, shard manifest (join the shards with `scatterlab "
        "experiment merge`)\n",
        r.runs.size(), r.rendered, r.resumed, r.failed, r.refused, out.c_str());
  else
    std::printf(
        "%zu runs: %d rendered, %d resumed, %d failed, %d refused (the method cannot render "
        "the scene); wrote %s/report.html, report.md, "
        "results.csv, "
        "results.json, images/, log.txt%s\n",
        r.runs.size(), r.rendered, r.resumed, r.failed, r.refused, out.c_str(),
        r.plotsNote.empty() ? ", plots/" : "");
  if (r.failed) {
    // The tool's prefix and the first failure's reason (issue 37: only a count and the log).
    const RunRecord* first = nullptr;
    for (const RunRecord& run : r.runs)
      if (run.status == "failed") {
        first = &run;
        break;
      }
    std::fprintf(stderr, "scatterlab: error: %d run%s failed%s%s%s; see %s/log.txt\n", r.failed,
                 r.failed == 1 ? "" : "s", first ? " (the first, " : "",
                 first ? (first->id + ": " + first->error).c_str() : "", first ? ")" : "",
                 out.c_str());
    return 1;
  }
  return 0;
}

}  // namespace

Action addExperiment(CLI::App& app) {
  struct Opts {
    std::string config, out, shard, mergeOut;
    std::vector<std::string> sets, mergeDirs;
    bool quiet = false, noPlots = false, noProgress = false, list = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* c = app.add_subcommand(
      "experiment",
      "Run an experiment config (scenes x methods x sweeps, docs/harness.md): images, "
      "results.csv, results.json, report.md, report.html, plots; resumes an interrupted sweep. "
      "`experiment merge DIR... -o OUT` joins the outputs of --shard runs");
  c->add_option("config", o->config, "Experiment config (JSON), e.g. data/experiments/fig3.json");
  c->add_option("-o,--output", o->out, "Output directory (created if missing; reused to resume)");
  c->add_option("--set", o->sets, "Scene override applied to every render (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  c->add_option("--shard", o->shard,
                "K/N: render only the K-th of N deterministic slices of the runs (no report: "
                "join the shards with `experiment merge`)")
      ->check([](const std::string& s) { return parseShard(s); });
  c->add_flag("--list", o->list,
              "Check the config and print its run ids (those of --shard K/N when given), one a "
              "line; renders nothing, needs no -o");
  c->add_flag("-q,--quiet", o->quiet, "No per-run log on stderr (DIR/log.txt is still written)");
  c->add_flag("--no-plots", o->noPlots, "Do not call experiment/plots.py");
  c->add_flag("--no-progress", o->noProgress, "No progress bar");
  CLI::App* m = c->add_subcommand(
      "merge",
      "Join the output directories of `experiment CONFIG -o DIR --shard K/N` runs into "
      "one results.csv/json, report.md, report.html, gallery and plots");
  m->add_option("dirs", o->mergeDirs, "Shard output directories (all N shards between them)")
      ->required();
  m->add_option("-o,--output", o->mergeOut, "Output directory of the merged experiment")
      ->required();
  m->add_flag("-q,--quiet", o->quiet, "No per-run log on stderr");
  m->add_flag("--no-plots", o->noPlots, "Do not call experiment/plots.py");
  m->add_flag("--no-progress", o->noProgress, "No progress bar");
  c->require_subcommand(0, 1);
  return [o, m]() {
    checkSetOptions(o->sets);
    ExperimentOptions opt;
    opt.overrides = o->sets;
    opt.log = o->quiet ? nullptr : stderr;
    opt.progress = !o->noProgress;
    opt.plots = !o->noPlots;
    if (m->parsed()) {
      if (!o->config.empty() || !o->shard.empty() || !o->sets.empty())
        throw UsageError(
            "experiment merge: takes DIR... -o OUT only (the config and overrides come from "
            "the shards' manifests)");
      const ExperimentResult r = mergeShards(o->mergeDirs, o->mergeOut, opt);
      return printSummary(r, o->mergeOut, false);
    }
    if (o->list && !o->config.empty()) {
      int k = 0, n = 0;
      if (!o->shard.empty()) parseShard(o->shard, &k, &n);
      const ExperimentPlan plan = parseExperiment(o->config, o->sets);
      const std::vector<int> owner = shardOf(plan, std::max(n, 1));
      for (std::size_t i = 0; i < plan.runs.size(); ++i)
        if (n == 0 || owner[i] == k - 1) std::printf("%s\n", plan.runs[i].id.c_str());
      return 0;
    }
    if (o->config.empty() || o->out.empty())
      throw UsageError("experiment: give CONFIG and -o DIR (or `experiment merge DIR... -o OUT`)");
    if (!o->shard.empty()) parseShard(o->shard, &opt.shardIndex, &opt.shardCount);
    const ExperimentResult r = runExperiment(o->config, o->out, opt);
    return printSummary(r, o->out, !o->shard.empty());
  };
}

}  // namespace scatterlab::cli
