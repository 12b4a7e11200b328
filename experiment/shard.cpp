// Sweeps split across processes or machines: the deterministic slices of `--shard K/N`, the
// shard manifests, `scatterlab experiment merge`, and the machine facts every record carries.

#include <sched.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>

#include "core/atomic_file.h"
#include "core/error.h"
#include "experiment/detail.h"

#ifndef SCATTERLAB_SOURCE_DIR
#define SCATTERLAB_SOURCE_DIR "."
#endif

namespace scatterlab {

namespace fs = std::filesystem;

namespace {

/// The first line of `cmd`'s standard output ("" when it fails).
std::string firstLine(const std::string& cmd) {
  std::FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return "";
  char buf[512];
  std::string out;
  if (std::fgets(buf, sizeof buf, p)) out = buf;
  ::pclose(p);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}

std::string cpuModel() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      const auto c = line.find(':');
      if (c != std::string::npos) return line.substr(line.find_first_not_of(" \t", c + 1));
    }
  return "unknown";
}

}  // namespace

Json machineFacts() {
  Json m;
  m["cpu_model"] = cpuModel();
  m["logical_cpus"] = ::sysconf(_SC_NPROCESSORS_ONLN);
  cpu_set_t set;
  CPU_ZERO(&set);
  m["cores_used"] = ::sched_getaffinity(0, sizeof set, &set) == 0 ? CPU_COUNT(&set)
                                                                  : m["logical_cpus"].get<int>();
  double load[3] = {0, 0, 0};
  std::ifstream la("/proc/loadavg");
  if (la >> load[0] >> load[1] >> load[2])
    m["load_avg_start"] = {load[0], load[1], load[2]};
  else
    m["load_avg_start"] = nullptr;
  char host[256] = {0};
  ::gethostname(host, sizeof host - 1);
  m["hostname"] = host;
  utsname u{};
  m["os"] = ::uname(&u) == 0 ? std::string(u.sysname) + " " + u.release : "unknown";
  const std::string git = "git -C '" + std::string(SCATTERLAB_SOURCE_DIR) + "' ";
  std::string commit = firstLine(git + "rev-parse --short=12 HEAD 2>/dev/null");
  if (commit.empty())
    commit = "unknown";
  else if (!firstLine(git + "status --porcelain --untracked-files=no 2>/dev/null").empty())
    commit += "+dirty";
  m["commit"] = commit;
  return m;
}

namespace detail {

std::string referenceGroup(const RunSpec& r) {
  const Json key = {{"scene", readText(r.sceneSpec->file)},
                    {"sets", r.refSets},
                    {"lights", r.refLights ? Json(*r.refLights) : Json()}};
  return stableHash(key.dump());
}

}  // namespace detail

std::vector<int> shardOf(const ExperimentPlan& plan, int count) {
  std::vector<int> out(plan.runs.size(), 0);
  if (count <= 1) return out;
  std::vector<std::string> order;
  std::map<std::string, std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < plan.runs.size(); ++i) {
    const std::string g = detail::referenceGroup(plan.runs[i]);
    if (!groups.count(g)) order.push_back(g);
    groups[g].push_back(i);
  }
  if (int(order.size()) < count) {
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = int(i % std::size_t(count));
    return out;
  }
  std::vector<std::size_t> load(std::size_t(count), 0);
  for (const std::string& g : order) {
    const int s = int(std::min_element(load.begin(), load.end()) - load.begin());
    for (std::size_t i : groups[g]) out[i] = s;
    load[std::size_t(s)] += groups[g].size();
  }
  return out;
}

namespace {

struct Manifest {
  std::string dir, file;
  Json j;
};

std::string planHash(const ExperimentPlan& plan) {
  std::string s;
  for (const RunSpec& r : plan.runs) s += r.id + ":" + r.hash + ";";
  return stableHash(s);
}

}  // namespace

namespace detail {

/// Written by a shard when its slice is done: what merge needs to find and check it.
void writeShardManifest(const ExperimentResult& res, const std::string& configPath,
                        const ExperimentOptions& opt, const std::vector<char>& selected,
                        OutputDir& out) {
  Json ids = Json::array();
  for (std::size_t i = 0; i < res.plan.runs.size(); ++i)
    if (selected[i]) ids.push_back(res.plan.runs[i].id);
  const Json j = {{"config", fs::absolute(configPath).lexically_normal().string()},
                  {"overrides", opt.overrides},
                  {"shard", opt.shardIndex},
                  {"shards", opt.shardCount},
                  {"plan_hash", planHash(res.plan)},
                  {"runs", ids},
                  {"rendered", res.rendered},
                  {"resumed", res.resumed},
                  {"failed", res.failed},
                  {"machine", res.machine},
                  {"finished", nowIso()}};
  writeText(out.path("shard-" + std::to_string(opt.shardIndex) + "-of-" +
                     std::to_string(opt.shardCount) + ".json"),
            j.dump(2) + "\n");
}

}  // namespace detail

ExperimentResult mergeShards(const std::vector<std::string>& dirs, const std::string& outDir,
                             const ExperimentOptions& opt) {
  if (dirs.empty()) throw ConfigError("merge: give at least one shard directory");
  std::vector<Manifest> manifests;
  for (const std::string& d : dirs) {
    if (!fs::is_directory(d)) throw IoError("merge: '" + d + "' is not a directory");
    bool any = false;
    for (const auto& e : fs::directory_iterator(d)) {
      const std::string name = e.path().filename().string();
      if (name.rfind("shard-", 0) != 0 || e.path().extension() != ".json") continue;
      manifests.push_back({d, e.path().string(), readJsonFile(e.path().string())});
      any = true;
    }
    if (!any)
      throw ConfigError("merge: '" + d +
                        "' holds no shard-K-of-N.json (written by `scatterlab experiment CONFIG "
                        "-o DIR --shard K/N` when its slice is done)");
  }
  const Json& first = manifests.front().j;
  const int count = first.value("shards", 0);
  std::map<int, const Manifest*> byShard;
  for (const Manifest& m : manifests) {
    for (const char* k : {"config", "overrides", "shards", "plan_hash"})
      if (m.j.value(k, Json()) != first.value(k, Json()))
        throw ConfigError("merge: '" + m.file + "' belongs to another experiment than '" +
                          manifests.front().file + "' (its '" + k + "' differs)");
    byShard.emplace(m.j.value("shard", 0), &m);
  }
  std::string missing;
  for (int k = 1; k <= count; ++k)
    if (!byShard.count(k)) missing += (missing.empty() ? "" : ", ") + std::to_string(k);
  if (!missing.empty())
    throw ConfigError("merge: shard(s) " + missing + " of " + std::to_string(count) +
                      " missing from the directories given (a shard writes "
                      "shard-K-of-N.json when its slice is done)");
  const std::string config = first.value("config", "");
  ExperimentOptions o = opt;
  o.overrides = first.value("overrides", std::vector<std::string>{});
  const ExperimentPlan plan = parseExperiment(config, o.overrides);
  if (planHash(plan) != first.value("plan_hash", ""))
    throw ConfigError("merge: the config '" + config +
                      "' or a scene file changed since the shards ran (its runs' configuration "
                      "hashes differ); run the shards again");
  // Every run's record, in the directory of the shard that owned it.
  std::map<std::string, std::string> recordDir;
  for (const auto& [k, m] : byShard)
    for (const Json& id : m->j.value("runs", Json::array())) {
      const std::string rec = (fs::path(m->dir) / "runs" / (id.get<std::string>() + ".json"));
      if (!fs::exists(rec))
        throw ConfigError("merge: run '" + id.get<std::string>() + "' of shard " +
                          std::to_string(k) + " has no record '" + rec +
                          "'; run that shard again (it resumes)");
      recordDir[id.get<std::string>()] = m->dir;
    }
  for (const RunSpec& r : plan.runs)
    if (!recordDir.count(r.id)) throw ConfigError("merge: run '" + r.id + "' is in no shard");
  // Copy what the report needs; a shard directory may be the output directory itself.
  createOutputDirectory(outDir);
  for (const char* sub : {"runs", "images", "references"})
    createOutputDirectory((fs::path(outDir) / sub).string());
  const auto copy = [&](const fs::path& from, const fs::path& to) {
    if (!fs::exists(from)) return;
    if (fs::exists(to) && fs::equivalent(from, to)) return;
    fs::copy_file(from, to, fs::copy_options::overwrite_existing);
  };
  for (const auto& [id, d] : recordDir) {
    copy(fs::path(d) / "runs" / (id + ".json"), fs::path(outDir) / "runs" / (id + ".json"));
    for (const char* ext : {".exr", ".png"})
      copy(fs::path(d) / "images" / (id + ext), fs::path(outDir) / "images" / (id + ext));
  }
  for (const auto& [k, m] : byShard)
    if (fs::is_directory(fs::path(m->dir) / "references"))
      for (const auto& e : fs::directory_iterator(fs::path(m->dir) / "references"))
        if (e.is_regular_file() &&
            !fs::exists(fs::path(outDir) / "references" / e.path().filename()))
          copy(e.path(), fs::path(outDir) / "references" / e.path().filename());
  {
    detail::OutputDir out(outDir);
    for (const auto& [k, m] : byShard)
      out.log("merge: shard " + std::to_string(k) + "/" + std::to_string(count) + " from " +
              m->dir + " (" + std::to_string(m->j.value("rendered", 0)) + " rendered, " +
              std::to_string(m->j.value("resumed", 0)) + " resumed, " +
              std::to_string(m->j.value("failed", 0)) + " failed; machine " +
              m->j.value("machine", Json::object()).value("hostname", "?") + ")");
  }
  o.recordsOnly = true;
  o.shardIndex = o.shardCount = 0;
  return runExperiment(config, outDir, o);
}

}  // namespace scatterlab
