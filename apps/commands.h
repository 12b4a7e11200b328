#pragma once
/// Subcommands of the `scatterlab` tool. Each registers its options on the CLI11 app and
/// returns the action to run when it was chosen. Actions throw scatterlab::Error on failure;
/// main() turns that into a message on stderr and exit code 1.

#include <CLI/CLI.hpp>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/params.h"

namespace scatterlab::cli {

using Action = std::function<int()>;

/// A command line that is wrong as a whole (CLI11 checks options one by one): main() prints it
/// like CLI11's errors and exits 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throws UsageError when two of the named paths (option, path; empty paths skipped) are the
/// same file, e.g. `-o o.exr --png o.exr`: one would silently overwrite the other. Each path is
/// compared as the canonical path of its directory (".", "..", symbolic links resolved, made
/// absolute) plus its file name, and an existing file or symbolic link as its canonical path,
/// so `o.exr`, `./o.exr`, `$PWD/o.exr`, `sub/../o.exr` and `link-to-dir/o.exr` are one file
/// whether or not it exists yet.
inline std::filesystem::path identityOf(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path abs = fs::absolute(path, ec);
  if (ec) return fs::path(path).lexically_normal();
  if (fs::exists(fs::symlink_status(abs, ec))) {
    const fs::path canon = fs::canonical(abs, ec);  // follows a final symbolic link
    if (!ec) return canon;
  }
  const fs::path name = abs.filename();
  if (name.empty() || name == "." || name == "..") {
    const fs::path whole = fs::weakly_canonical(abs, ec);
    return ec ? abs.lexically_normal() : whole;
  }
  const fs::path dir = fs::weakly_canonical(abs.parent_path(), ec);
  return ec ? abs.lexically_normal() : dir / name;
}

inline void checkDistinctPaths(const std::vector<std::pair<std::string, std::string>>& named) {
  std::vector<std::pair<std::string, std::filesystem::path>> seen;
  for (const auto& [option, path] : named) {
    if (path.empty()) continue;
    const std::filesystem::path canon = identityOf(path);
    for (const auto& [otherOption, other] : seen)
      if (other == canon)
        throw UsageError(otherOption + " and " + option + " name the same file '" + path +
                         "'; give each output its own path");
    seen.emplace_back(option, canon);
  }
}

/// Throws UsageError unless every `--set` is KEY=VALUE with a well-formed key path
/// (checkOverrideSyntax), before any work (issue 37: '=' was accepted, then every render failed).
inline void checkSetOptions(const std::vector<std::string>& sets) {
  for (const std::string& a : sets) {
    if (a.find('=') == std::string::npos)
      throw UsageError("--set '" + a + "': expected KEY=VALUE, e.g. --set " +
                       (a.empty() ? std::string("camera.width") : a) + "=640");
    try {
      checkOverrideSyntax(a);  // '=', '.x=1', 'a..b=1'
    } catch (const ConfigError& e) {
      throw UsageError(e.what());
    }
  }
}

/// The image format a path asks for, by extension (case-insensitive): "exr", "png" or "".
inline std::string imageFormat(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& ch : ext) ch = char(std::tolower((unsigned char)ch));
  return ext == ".exr" ? "exr" : ext == ".png" ? "png" : "";
}

/// The check of a PNG exposure option (`render --exposure`, `convert --exposure`): a number of
/// stops in [-100, 100] (writePng's range; NaN and inf refused).
inline CLI::Validator exposureValidator() {
  return CLI::Validator(
      [](std::string& v) -> std::string {
        char* end = nullptr;
        const double x = std::strtod(v.c_str(), &end);
        return end != v.c_str() && *end == 0 && std::abs(x) <= 100.0
                   ? ""
                   : "'" + v + "' is not a number of stops in [-100, 100]";
      },
      "STOPS in [-100, 100]");
}

/// Throws IoError when `path` is a PNG (its 8 signature bytes, whatever its extension) where a
/// linear OpenEXR is needed: `what` names the argument ("image", "reference", "input"), `need`
/// says who needs the EXR ("compare needs", "convert reads"). Missing, unreadable and special
/// files are refused first (checkReadableFile), so that nothing blocks on a FIFO.
inline void refusePng(const std::string& path, const std::string& what, const std::string& need) {
  checkReadableFile(path, what);
  std::ifstream f(path, std::ios::binary);
  char head[8] = {};
  if (!f.read(head, sizeof head)) return;
  if (std::string(head, sizeof head) != std::string("\x89PNG\r\n\x1a\n", 8)) return;
  throw IoError(what + " '" + path + "' is a PNG (8-bit, display-encoded); " + need +
                " linear OpenEXR images (the .exr that render -o writes; its PNGs are display "
                "copies)");
}

Action addRender(CLI::App& app);
Action addCompare(CLI::App& app);
Action addConvert(CLI::App& app);
Action addInfo(CLI::App& app);
Action addFit(CLI::App& app);
Action addExperiment(CLI::App& app);

}  // namespace scatterlab::cli
