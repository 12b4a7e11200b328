#include "core/limits.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "core/error.h"
#include "core/work_limits.h"

namespace scatterlab {

namespace {

constexpr const char* kEnv = "SCATTERLAB_MEMORY_LIMIT";

std::atomic<std::uint64_t> g_limit{0};  // 0: not set yet

std::uint64_t physicalMemory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return std::uint64_t(8) << 30;  // unknown: assume 8 GiB
  return std::uint64_t(pages) * std::uint64_t(page);
}

std::uint64_t initialLimit() {
  if (const char* e = std::getenv(kEnv); e && *e) return parseMemorySize(e, kEnv);
  return defaultMemoryLimit();
}

}  // namespace

std::uint64_t defaultMemoryLimit() {
  const std::uint64_t physical = physicalMemory() / 4 * 3;
  // Under an address-space limit (ulimit -v, a container's) the process fails at what is
  // left of it, not at physical memory: half the room the limit leaves above what is mapped
  // now, so that a request above it is refused with its key instead of ending in
  // std::bad_alloc after seconds of work. Half, not 75 %: address space goes also to what the
  // plan does not count (malloc's per-thread arenas of 64 MiB, thread stacks, the stages'
  // working arrays); per-voxel at 320^3 plans 1000 MiB and failed under 1.5 GiB.
  rlimit as{};
  if (::getrlimit(RLIMIT_AS, &as) != 0 || as.rlim_cur == RLIM_INFINITY) return physical;
  std::uint64_t mapped = 0;
  if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
    unsigned long long pages = 0;
    if (std::fscanf(f, "%llu", &pages) == 1) mapped = pages * std::uint64_t(sysconf(_SC_PAGE_SIZE));
    std::fclose(f);
  }
  const std::uint64_t cap = std::uint64_t(as.rlim_cur);
  const std::uint64_t room = cap > mapped ? cap - mapped : 0;
  return std::max<std::uint64_t>(std::min(physical, room / 2), std::uint64_t(1) << 20);
}

std::uint64_t memoryLimit() {
  std::uint64_t l = g_limit.load(std::memory_order_relaxed);
  if (l == 0) {
    l = initialLimit();
    g_limit.store(l, std::memory_order_relaxed);
  }
  return l;
}

void setMemoryLimit(std::uint64_t bytes) {
  g_limit.store(bytes == 0 ? initialLimit() : bytes, std::memory_order_relaxed);
}

std::uint64_t parseMemorySize(const std::string& text, const std::string& what) {
  const auto bad = [&](const std::string& why) {
    return ConfigError((what.empty() ? "" : what + ": ") + "'" + text.substr(0, 40) + "' " + why +
                       "; expected bytes with an optional unit (K, M, G, T) or a percentage "
                       "of physical memory, e.g. 4G, 512M, 50%");
  };
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    throw bad("is not a size");
  }
  std::string unit = text.substr(used);
  unit.erase(0, unit.find_first_not_of(' '));
  for (char& c : unit) c = char(std::tolower(static_cast<unsigned char>(c)));
  double bytes = 0;
  if (unit == "%") {
    if (!(v > 0 && v <= 100)) throw bad("is not a percentage in (0, 100]");
    bytes = double(physicalMemory()) * v / 100.0;
  } else {
    static const char* kUnits = "bkmgt";
    double scale = 1;
    if (!unit.empty()) {
      const char* u = std::strchr(kUnits, unit[0]);
      const std::string rest = unit.substr(1);
      if (!u || !(rest.empty() || rest == "b" || rest == "ib" || (unit == "b")))
        throw bad("has an unknown unit '" + unit.substr(0, 8) + "'");
      scale = std::pow(1024.0, double(u - kUnits));
    }
    if (!(std::isfinite(v) && v > 0)) throw bad("is not a positive size");
    bytes = v * scale;
  }
  if (!(bytes >= double(1 << 20))) throw bad("is below 1 MiB");
  if (!(bytes < 1.8e19)) throw bad("is too large");
  return std::uint64_t(bytes);
}

std::string formatBytes(double bytes) {
  static const char* kNames[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int u = 0;
  while (bytes >= 1024.0 && u < 6) {
    bytes /= 1024.0;
    ++u;
  }
  char buf[48];
  if (u == 0)
    std::snprintf(buf, sizeof buf, "%.0f bytes", bytes);
  else
    std::snprintf(buf, sizeof buf, "%.*f %s", bytes < 10 ? 1 : 0, bytes, kNames[u]);
  return buf;
}

void checkMemory(const std::string& key, const std::string& what, double bytes) {
  const std::uint64_t limit = memoryLimit();
  if (!(bytes > double(limit))) return;
  throw LimitError("'" + key + "': " + what + " needs about " + formatBytes(bytes) +
                   ", above the memory limit of " + formatBytes(double(limit)) +
                   " (the default is 75 % of physical memory, under ulimit -v half of what it "
                   "leaves; change the limit with --memory-limit or " +
                   kEnv + ")");
}

std::string formatCount(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

void MemoryPlan::add(std::vector<std::string> keys, const std::string& what, double bytes) {
  if (bytes > 0) items_.push_back({std::move(keys), what, bytes});
}

double MemoryPlan::total() const {
  double t = 0;
  for (const Item& i : items_) t += i.bytes;
  return t;
}

void MemoryPlan::check() const {
  const std::uint64_t limit = memoryLimit();
  const double sum = total();
  if (!(sum > double(limit))) return;
  std::vector<Item> largest = items_;
  std::stable_sort(largest.begin(), largest.end(),
                   [](const Item& a, const Item& b) { return a.bytes > b.bytes; });
  std::string parts;
  for (std::size_t i = 0; i < largest.size() && i < 3; ++i) {
    std::string keys;
    for (const std::string& k : largest[i].keys) keys += (keys.empty() ? "'" : ", '") + k + "'";
    parts +=
        (i ? "; " : "") + (keys + ": " + largest[i].what + ", " + formatBytes(largest[i].bytes));
  }
  if (largest.size() > 3)
    parts += "; and " + std::to_string(largest.size() - 3) + " smaller, " +
             formatBytes(sum - largest[0].bytes - largest[1].bytes - largest[2].bytes);
  throw LimitError("the render's planned allocations need about " + formatBytes(sum) +
                   " in all, above the memory limit of " + formatBytes(double(limit)) +
                   "; the largest: " + parts +
                   " (the default limit is 75 % of physical memory, under ulimit -v half of what "
                   "it leaves; change it with "
                   "--memory-limit or " +
                   kEnv + ")");
}

}  // namespace scatterlab
