#include "experiment/experiment.h"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"

namespace scatterlab {

namespace {

std::vector<std::string> stringList(Params& p, const std::string& key) {
  std::vector<std::string> out;
  if (!p.has(key)) {
    p.allow(key);
    return out;
  }
  const Json& j = p.raw(key);
  if (!j.is_array()) p.fail(key, "expected an array of strings, got " + describeValue(j));
  for (const Json& v : j) {
    if (!v.is_string()) p.fail(key, "expected an array of strings, got " + describeValue(v));
    out.push_back(v.get<std::string>());
  }
  return out;
}

double stageMs(const RenderStats& s, const std::string& stage) {
  for (const auto& [n, ms] : s.timingsMs)
    if (n == stage) return ms;
  return 0.0;
}

std::string fmt(double v, const char* f = "%.4g") {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

void writeText(const std::string& path, const std::string& text) {
  writeAtomically(path, [&](const std::string& tmp) {
    std::ofstream f(tmp);
    f << text;
    if (!f) throw IoError("cannot write '" + path + "'");
  });
}

/// Images side by side, left to right, with a 4-pixel black gap.
Image sideBySide(const std::vector<const Image*>& imgs) {
  int w = 0, h = 0;
  for (const Image* i : imgs) {
    w += i->width() + 4;
    h = std::max(h, i->height());
  }
  Image out(std::max(0, w - 4), h);
  int x0 = 0;
  for (const Image* i : imgs) {
    for (int y = 0; y < i->height(); ++y)
      for (int x = 0; x < i->width(); ++x) out.at(x0 + x, y) = i->at(x, y);
    x0 += i->width() + 4;
  }
  return out;
}

}  // namespace

ExperimentResult runExperiment(const std::string& configPath, const std::string& outDir,
                               const std::vector<std::string>& overrides, std::FILE* log) {
  const Json cfg = readJsonFile(configPath);
  Params p(cfg, "");
  ExperimentResult res;
  res.title = p.string("title", std::string("experiment"));
  const std::filesystem::path base = std::filesystem::path(configPath).parent_path();
  const std::string scenePath = (base / p.string("scene")).string();
  std::vector<std::string> sets = stringList(p, "set");
  sets.insert(sets.end(), overrides.begin(), overrides.end());
  res.references = stringList(p, "references");
  if (res.references.empty()) p.fail("references", "give at least one reference method");
  const float exposure = p.real("exposure", 0.0);
  struct Run {
    std::string name, method;
    std::vector<std::string> sets;
    std::optional<double> paper;
  };
  std::vector<Run> runs;
  for (Params r : p.children("runs", true)) {
    Run run;
    run.name = r.string("name");
    run.method = r.string("method");
    run.sets = stringList(r, "set");
    if (r.has("paper_rel_error"))
      run.paper = r.number("paper_rel_error", std::nullopt, Interval::atLeast(0));
    else
      r.allow("paper_rel_error");
    for (char c : run.name)
      if (!std::isalnum((unsigned char)c) && c != '-' && c != '_')
        r.fail("name",
               "'" + run.name + "' must use only letters, digits, '-' and '_' (it names files)");
    r.finish();
    runs.push_back(run);
  }
  p.finish();
  std::filesystem::create_directories(outDir);
  const auto out = [&](const std::string& f) {
    return (std::filesystem::path(outDir) / f).string();
  };

  std::vector<Image> images;
  const auto renderOne = [&](const std::string& name, const std::string& method,
                             const std::vector<std::string>& extra, bool reference,
                             std::optional<double> paper) {
    std::vector<std::string> all = sets;
    // A run's settings are validated by its own method: it becomes the scene's render.method.
    if (!reference) all.push_back("render.method=" + method);
    all.insert(all.end(), extra.begin(), extra.end());
    const Scene scene = loadScene(scenePath, all);
    RenderResult r = createMethod(scene, method, "cpu")->render(scene, nullptr);
    writeExr(r.image, out(name + ".exr"));
    writePng(r.image, out(name + ".png"), exposure);
    ExperimentRow row;
    row.name = name;
    row.method = method;
    row.reference = reference;
    row.stats = r.stats;
    row.paperRelError = paper;
    if (log)
      std::fprintf(
          log, "%-14s %-10s %9.1f ms%s\n", name.c_str(), method.c_str(), r.stats.totalMs(),
          r.stats.samples ? (", " + std::to_string(*r.stats.samples) + " samples").c_str() : "");
    res.rows.push_back(std::move(row));
    images.push_back(std::move(r.image));
  };
  for (const std::string& ref : res.references) renderOne(ref, ref, {}, true, std::nullopt);
  for (const Run& run : runs) renderOne(run.name, run.method, run.sets, false, run.paper);
  for (std::size_t i = 0; i < res.rows.size(); ++i)
    for (std::size_t k = 0; k < res.references.size(); ++k)
      res.rows[i].errors.push_back(compareImages(images[i], images[k]));

  // Tables.
  std::ostringstream csv, md;
  csv << "name,method,samples,total_ms,sampling_ms,evaluation_ms,reconstruction_ms,march_ms,"
         "uncovered_voxels";
  for (const auto& r : res.references) csv << ",rel_l2_vs_" << r << ",rel_l1_vs_" << r;
  csv << ",paper_rel_error\n";
  md << "# " << res.title << "\n\nScene `" << p.json()["scene"].get<std::string>()
     << "`. Relative L2 = sqrt(Σ(a−b)²)/sqrt(Σb²), relative L1 = Σ|a−b|/Σ|b| over all pixels "
        "and channels (DESIGN.md §2). Images left to right in side_by_side.png: the rows of "
        "this table, top to bottom.\n\n| image | method | samples |";
  for (const auto& r : res.references) md << " rel L2 vs " << r << " | rel L1 vs " << r << " |";
  md << " paper | time (ms) | sampling + evaluation + reconstruction (ms) |\n|---|---|---|";
  for (std::size_t k = 0; k < res.references.size(); ++k) md << "---|---|";
  md << "---|---|---|\n";
  Json j;
  j["title"] = res.title;
  j["rows"] = Json::array();
  for (const ExperimentRow& r : res.rows) {
    const auto& s = r.stats;
    const long long unc =
        s.extra.contains("uncovered_voxels") ? s.extra["uncovered_voxels"].get<long long>() : 0;
    csv << r.name << "," << r.method << "," << (s.samples ? std::to_string(*s.samples) : "") << ","
        << fmt(s.totalMs(), "%.1f") << "," << fmt(stageMs(s, "sampling"), "%.1f") << ","
        << fmt(stageMs(s, "evaluation"), "%.1f") << "," << fmt(stageMs(s, "reconstruction"), "%.1f")
        << "," << fmt(stageMs(s, "march"), "%.1f") << "," << unc;
    md << "| " << r.name << " | " << r.method << " | "
       << (s.samples ? std::to_string(*s.samples) : "—") << " |";
    Json jr = s.toJson();
    jr["name"] = r.name;
    for (std::size_t k = 0; k < r.errors.size(); ++k) {
      csv << "," << fmt(r.errors[k].relL2, "%.6f") << "," << fmt(r.errors[k].relL1, "%.6f");
      md << " " << fmt(100 * r.errors[k].relL2, "%.2f") << "% | "
         << fmt(100 * r.errors[k].relL1, "%.2f") << "% |";
      jr["rel_l2_vs_" + res.references[k]] = r.errors[k].relL2;
      jr["rel_l1_vs_" + res.references[k]] = r.errors[k].relL1;
    }
    csv << "," << (r.paperRelError ? fmt(*r.paperRelError, "%.4f") : "") << "\n";
    md << " " << (r.paperRelError ? fmt(100 * *r.paperRelError, "%.1f") + "%" : "—") << " | "
       << fmt(s.totalMs(), "%.0f") << " | "
       << (s.samples ? fmt(stageMs(s, "sampling") + stageMs(s, "evaluation") +
                               stageMs(s, "reconstruction"),
                           "%.0f")
                     : "—")
       << " |\n";
    if (r.paperRelError) jr["paper_rel_error"] = *r.paperRelError;
    j["rows"].push_back(jr);
  }
  writeText(out("results.csv"), csv.str());
  writeText(out("results.md"), md.str());
  writeText(out("results.json"), j.dump(2) + "\n");
  std::vector<const Image*> ptrs;
  for (const Image& i : images) ptrs.push_back(&i);
  writePng(sideBySide(ptrs), out("side_by_side.png"), exposure);
  return res;
}

}  // namespace scatterlab
