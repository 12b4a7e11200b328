// The experiment harness's shared helpers (declared in experiment/detail.h): formatting, text
// files, labels and the output directory with its log.

#include "experiment/detail.h"

#include <signal.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"

namespace scatterlab::detail {

namespace fs = std::filesystem;

std::string fmt(double v, const char* format) {
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

std::string readText(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

void writeText(const std::string& path, const std::string& text) {
  writeBytesAtomically(path, text);
}

std::string fileSafe(std::string s) {
  for (char& c : s)
    if (!std::isalnum((unsigned char)c) && c != '-' && c != '_' && c != '.') c = '_';
  return s;
}

std::string valueLabel(const Json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_array()) {
    std::string s;
    for (const Json& e : v) {
      if (!s.empty()) s += 'x';
      s += valueLabel(e);
    }
    return s;
  }
  if (v.is_number_float()) {
    const double d = v.get<double>();
    if (d == std::floor(d) && std::fabs(d) < 1e15) return std::to_string((long long)d);
    return fmt(d, "%g");
  }
  return v.dump();
}

std::string nowIso() {
  const std::time_t t = std::time(nullptr);
  char b[64];
  std::strftime(b, sizeof b, "%Y-%m-%d %H:%M:%S", std::localtime(&t));
  return b;
}

/// Removes temporaries of core/atomic_file ('.NAME.tmpPID_N') that a killed process left in
/// `dir` and its subfolders: resume would otherwise never remove them. Temporaries of live
/// processes (a concurrent writer) are kept.
static void removeStaleTemporaries(const fs::path& dir) {
  std::error_code ec;
  std::vector<fs::path> stale;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::end(it);
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const auto at = name.rfind(".tmp");
    if (name.empty() || name[0] != '.' || at == std::string::npos) continue;
    const std::string tail = name.substr(at + 4);
    const auto underscore = tail.find('_');
    if (underscore == std::string::npos || underscore == 0 ||
        tail.find_first_not_of("0123456789_") != std::string::npos)
      continue;
    const long pid = std::strtol(tail.substr(0, underscore).c_str(), nullptr, 10);
    if (pid > 0 && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH) stale.push_back(it->path());
  }
  for (const fs::path& p : stale) fs::remove(p, ec);
}

OutputDir::OutputDir(const std::string& dir) : dir_(dir) {
  if (fs::is_directory(dir)) removeStaleTemporaries(dir);
  fs::create_directories(fs::path(dir) / "runs");
  fs::create_directories(fs::path(dir) / "images");
  fs::create_directories(fs::path(dir) / "references");
  log_.open(path("log.txt"), std::ios::app);
}

std::string OutputDir::path(const std::string& file) const {
  return (fs::path(dir_) / file).string();
}

void OutputDir::log(const std::string& line) {
  log_ << "[" << nowIso() << "] " << line << "\n";
  log_.flush();
}

}  // namespace scatterlab::detail
