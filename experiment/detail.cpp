// The experiment harness's shared helpers (declared in experiment/detail.h): formatting, text
// files, labels and the output directory with its log.

#include "experiment/detail.h"

#include <signal.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <map>
#include <mutex>
#include <sstream>
#include <tuple>

#include "core/atomic_file.h"
#include "core/error.h"

namespace scatterlab::detail {

namespace fs = std::filesystem;

std::string fmt(double v, const char* format) {
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

std::string percent(double v, const char* format) {
  return std::isfinite(v) ? fmt(100 * v, format) + "%" : std::string("—");
}

std::string readText(const std::string& path) {
  // Only regular files: opening a FIFO would block (issue 37); the caller reports what is wrong.
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return "";
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

namespace {

/// stableHash of a file's bytes, cached while its size and modification time stay the same.
std::string fileHash(const fs::path& file) {
  static std::mutex mutex;
  static std::map<std::string, std::tuple<std::uintmax_t, fs::file_time_type, std::string>> cache;
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(file, ec);
  const fs::file_time_type time = ec ? fs::file_time_type() : fs::last_write_time(file, ec);
  if (!ec) {
    const std::lock_guard<std::mutex> lock(mutex);
    const auto it = cache.find(file.string());
    if (it != cache.end() && std::get<0>(it->second) == size && std::get<1>(it->second) == time)
      return std::get<2>(it->second);
  }
  const std::string h = stableHash(readText(file.string()));
  if (!ec) {
    const std::lock_guard<std::mutex> lock(mutex);
    cache[file.string()] = {size, time, h};
  }
  return h;
}

}  // namespace

std::string sceneHash(const std::string& sceneFile, const std::vector<std::string>& sets) {
  const std::string text = readText(sceneFile);
  std::string key = text;
  Json doc;
  try {
    doc = parseJson(text, "'" + sceneFile + "'");
  } catch (const Error&) {
    return stableHash(key);  // the run reports the error
  }
  // The run's overrides, where they apply (one that does not is the run's error to report).
  for (const std::string& a : sets) {
    try {
      applyOverride(doc, a);
    } catch (const Error&) {
    }
  }
  const fs::path dir = fs::path(sceneFile).parent_path();
  std::vector<std::string> names;
  const auto add = [&](const Json& j) {
    if (j.is_string()) names.push_back(j.get<std::string>());
  };
  if (doc.is_object() && doc.contains("medium") && doc["medium"].is_object() &&
      doc["medium"].contains("density") && doc["medium"]["density"].is_object()) {
    const Json& d = doc["medium"]["density"];
    if (d.contains("file")) add(d["file"]);
    if (d.contains("frames") && d["frames"].is_array())
      for (const Json& f : d["frames"]) add(f);
  }
  if (doc.is_object() && doc.contains("objects") && doc["objects"].is_array())
    for (const Json& o : doc["objects"])
      if (o.is_object() && o.contains("file")) add(o["file"]);
  for (const std::string& name : names) {
    const fs::path file = fs::path(name).is_absolute() ? fs::path(name) : dir / name;
    std::error_code ec;
    const bool regular = fs::is_regular_file(file, ec);
    key += '\n';
    key += name;
    key += ':';
    key += regular ? fileHash(file) : std::string("missing");
    // An OBJ's material libraries, relative to the OBJ.
    if (!regular || file.extension() != ".obj") continue;
    std::istringstream lines(readText(file.string()));
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind("mtllib", 0) != 0 || line.size() < 7 || !std::isspace((unsigned char)line[6]))
        continue;
      std::istringstream words(line.substr(7));
      for (std::string mtl; words >> mtl;) {
        const fs::path m = fs::path(mtl).is_absolute() ? fs::path(mtl) : file.parent_path() / mtl;
        // Appended piecewise: GCC 12 reports a false -Wrestrict for "\n" + std::string.
        key += '\n';
        key += m.string();
        key += ':';
        key += fs::is_regular_file(m, ec) ? stableHash(readText(m.string())) : "missing";
      }
    }
  }
  return stableHash(key);
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
  createOutputDirectory(dir);
  for (const char* sub : {"runs", "images", "references"})
    createOutputDirectory((fs::path(dir) / sub).string());
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
