#pragma once
/// Subcommands of the `scatterlab` tool. Each registers its options on the CLI11 app and
/// returns the action to run when it was chosen. Actions throw scatterlab::Error on failure;
/// main() turns that into a message on stderr and exit code 1.

#include <CLI/CLI.hpp>
#include <functional>

namespace scatterlab::cli {

using Action = std::function<int()>;

Action addRender(CLI::App& app);
Action addCompare(CLI::App& app);
Action addInfo(CLI::App& app);
Action addFit(CLI::App& app);
Action addExperiment(CLI::App& app);

}  // namespace scatterlab::cli
