/// `scatterlab`: render scenes, compare images, inspect files. See README.md.

#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <new>
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

namespace {

/// A message as one error on stderr: a value the user gave may be megabytes long or hold line
/// breaks (`--method $'x\nscatterlab: error: ...'` printed a fake second error line), so
/// continuation lines are indented and a message beyond 2000 characters keeps its first 1500
/// and last 300 with the count of what was left out.
std::string printable(std::string m) {
  if (m.size() > 2000)
    m = m.substr(0, 1500) + " [... " + std::to_string(m.size() - 1800) +
        " characters left out ...] " + m.substr(m.size() - 300);
  std::string out;
  for (char c : m) {
    out += c == '\r' ? ' ' : c;
    if (c == '\n') out += "  ";
  }
  return out;
}

void printError(const char* kind, const std::string& what, bool usage = false) {
  std::fprintf(stderr, "scatterlab: %s: %s\n%s", kind, printable(what).c_str(),
               usage ? "Run with --help for more information.\n" : "");
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
  add(scatterlab::cli::addConvert);
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
    printError("error", std::string(e.what()) + suggestOption(app, argc, argv), /*usage=*/true);
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
    printError("error", e.what(), /*usage=*/true);
    return 2;
  } catch (const scatterlab::Error& e) {
    printError("error", e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    // What the estimates did not foresee (docs/reliability.md: the plan counts what is certain).
    std::fprintf(stderr,
                 "scatterlab: error: out of memory: an allocation failed; lower the resolution "
                 "or image size, or give a --memory-limit below what the machine (or ulimit "
                 "-v) allows so that it is refused before the work\n");
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    // A file the library reached without a check of its own: the system's reason, not an
    // "internal error".
    printError("error", e.what());
    return 1;
  } catch (const std::exception& e) {
    printError("internal error", e.what());
    return 1;
  }
  return 1;
}
