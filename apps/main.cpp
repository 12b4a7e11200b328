/// `scatterlab`: render scenes, compare images, inspect files. See README.md.

#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "api/scatterlab.h"
#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/limits.h"
#include "core/suggest.h"

namespace {

/// For a misspelt option or subcommand on the command line: " (did you mean '--method'?)"
/// for the first word that is neither a known option nor a subcommand, else "".
std::string suggestOption(CLI::App& app, int argc, char** argv) {
  std::vector<std::string> options, subcommands;
  const auto addOptions = [&](const CLI::App& a) {
    for (const CLI::Option* o : a.get_options())
      for (const std::string& n : o->get_lnames()) options.push_back("--" + n);
  };
  addOptions(app);
  for (const CLI::App* sub : app.get_subcommands({})) {
    subcommands.push_back(sub->get_name());
    addOptions(*sub);
  }
  for (int i = 1; i < argc; ++i) {
    std::string word = argv[i];
    if (word.rfind("--", 0) == 0) {
      word = word.substr(0, word.find('='));
      if (std::find(options.begin(), options.end(), word) == options.end())
        return scatterlab::didYouMean(word, options);
    } else if (i == 1 && word.rfind('-', 0) != 0 &&
               std::find(subcommands.begin(), subcommands.end(), word) == subcommands.end()) {
      const std::string m = scatterlab::didYouMean(word, subcommands);
      return m.empty() ? std::string() : "; '" + word + "' is not a command" + m;
    }
  }
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "scatterlab: real-time single-scattering participating media, with references "
      "and comparisons"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string(scatterlab::version()));
  // Global options, accepted before or after the subcommand (docs/reliability.md).
  app.fallthrough();
  int threads = 0;
  app.add_option("--threads", threads,
                 "worker threads at most (TBB's global limit; default: one per core)")
      ->check(CLI::Range(1, 4096));
  std::string memoryLimit;
  app.add_option("--memory-limit", memoryLimit,
                 "refuse requests whose estimated memory is above this (bytes, K/M/G/T or % "
                 "of physical memory; default 75%, or SCATTERLAB_MEMORY_LIMIT)")
      ->check([](const std::string& v) -> std::string {
        try {
          scatterlab::parseMemorySize(v, "");
        } catch (const scatterlab::Error& e) {
          return e.what();
        }
        return {};
      });
  std::vector<std::pair<CLI::App*, scatterlab::cli::Action>> cmds;
  const auto add = [&](scatterlab::cli::Action (*f)(CLI::App&)) {
    const size_t before = app.get_subcommands({}).size();
    auto action = f(app);
    cmds.emplace_back(app.get_subcommands({})[before], action);
  };
  add(scatterlab::cli::addRender);
  add(scatterlab::cli::addCompare);
  add(scatterlab::cli::addInfo);
  add(scatterlab::cli::addFit);
  add(scatterlab::cli::addExperiment);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are CLI11 "errors" with code 0: let CLI11 print them.
    if (e.get_exit_code() == 0) return app.exit(e);
    // Usage errors exit with 2 (the project's rule), whatever CLI11's own code (105, 106, 109,
    // ...), with the same prefix as every other error.
    std::fprintf(stderr, "scatterlab: error: %s%s\nRun with --help for more information.\n",
                 e.what(), suggestOption(app, argc, argv).c_str());
    return 2;
  }
  std::unique_ptr<tbb::global_control> threadLimit;
  if (threads > 0)
    threadLimit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  try {
    if (!memoryLimit.empty())
      scatterlab::setMemoryLimit(scatterlab::parseMemorySize(memoryLimit, "--memory-limit"));
    scatterlab::initialize();
    scatterlab::removeTemporariesOnSignal();  // Ctrl-C leaves no temporary behind
    for (auto& [sub, action] : cmds)
      if (sub->parsed()) return action();
  } catch (const scatterlab::cli::UsageError& e) {
    std::fprintf(stderr, "scatterlab: error: %s\nRun with --help for more information.\n",
                 e.what());
    return 2;
  } catch (const scatterlab::Error& e) {
    std::fprintf(stderr, "scatterlab: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scatterlab: internal error: %s\n", e.what());
    return 1;
  }
  return 1;
}
