#pragma once
/// Subcommands of the `scatterlab` tool. Each registers its options on the CLI11 app and
/// returns the action to run when it was chosen. Actions throw scatterlab::Error on failure;
/// main() turns that into a message on stderr and exit code 1.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace scatterlab::cli {

using Action = std::function<int()>;

/// A command line that is wrong as a whole (CLI11 checks options one by one): main() prints it
/// like CLI11's errors and exits 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throws UsageError when two of the named paths (option, path; empty paths skipped) are the
/// same file, e.g. `-o o.exr --png o.exr`: one would silently overwrite the other. Paths are
/// compared after resolving "." / ".." and symbolic links of existing directories.
inline void checkDistinctPaths(const std::vector<std::pair<std::string, std::string>>& named) {
  std::vector<std::pair<std::string, std::filesystem::path>> seen;
  for (const auto& [option, path] : named) {
    if (path.empty()) continue;
    std::error_code ec;
    std::filesystem::path canon = std::filesystem::weakly_canonical(path, ec);
    if (ec) canon = std::filesystem::absolute(path, ec).lexically_normal();
    for (const auto& [otherOption, other] : seen)
      if (other == canon)
        throw UsageError(otherOption + " and " + option + " name the same file '" + path +
                         "'; give each output its own path");
    seen.emplace_back(option, canon);
  }
}

Action addRender(CLI::App& app);
Action addCompare(CLI::App& app);
Action addInfo(CLI::App& app);
Action addFit(CLI::App& app);
Action addExperiment(CLI::App& app);

}  // namespace scatterlab::cli
