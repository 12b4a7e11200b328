// The experiment's pictures: side-by-side strips of the references and the runs of each sweep
// point (report.md's gallery), and the plots made by experiment/plots.py.

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "core/scene.h"
#include "experiment/detail.h"

namespace scatterlab {

std::string findPlotPython() {
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("SCATTERLAB_PYTHON")) candidates.push_back(env);
  candidates.push_back("python3");
  candidates.push_back("/usr/bin/python3");
  for (const std::string& py : candidates) {
    const std::string cmd = "'" + py + "' -c 'import matplotlib' >/dev/null 2>&1";
    if (std::system(cmd.c_str()) == 0) return py;
  }
  return "";
}

namespace detail {

namespace fs = std::filesystem;

namespace {

/// Display-space difference shown at full colour in the signed error maps.
constexpr double kErrorMapFull = 0.1;

/// Images side by side, left to right, with a 4-pixel black gap.
Image sideBySide(const std::vector<Image>& imgs) {
  int w = 0, h = 0;
  for (const Image& i : imgs) {
    w += i.width() + 4;
    h = std::max(h, i.height());
  }
  Image out(std::max(0, w - 4), h);
  int x0 = 0;
  for (const Image& i : imgs) {
    for (int y = 0; y < i.height(); ++y)
      for (int x = 0; x < i.width(); ++x) out.at(x0 + x, y) = i.at(x, y);
    x0 += i.width() + 4;
  }
  return out;
}

/// Inverse of the sRGB curve: the linear value that toneMapSrgb (exposure 0) shows as `v`.
float srgbToLinear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

/// Signed error map of `img` against `ref` in display units (the visibly-wrong metric's): per
/// pixel Δ = mean over channels of toneMapSrgb(a) − toneMapSrgb(b); red where the image is
/// brighter, blue where darker, full at |Δ| = kErrorMapFull. Returned as linear values that show
/// as those colours after `exposure` stops.
Image signedErrorMap(const Image& img, const Image& ref, float exposure) {
  Image out(img.width(), img.height());
  const float unexpose = std::exp2(-exposure);
  for (std::size_t i = 0; i < out.pixels().size(); ++i) {
    float d = 0;
    for (int c = 0; c < 3; ++c)
      d += toneMapSrgb(img.pixels()[i][c]) - toneMapSrgb(ref.pixels()[i][c]);
    const float t = std::min(1.0f, std::abs(d / 3.0f) / float(kErrorMapFull));
    const float v = srgbToLinear(t) * unexpose;
    out.pixels()[i] = d > 0 ? Vec3(v, 0, 0) : Vec3(0, 0, v);
  }
  return out;
}

/// Images side by side (the first row) above their error maps (the second), 4-pixel gaps.
Image twoRows(const std::vector<Image>& top, const std::vector<Image>& bottom) {
  const Image a = sideBySide(top), b = sideBySide(bottom);
  Image out(std::max(a.width(), b.width()), a.height() + 4 + b.height());
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x) out.at(x, y) = a.at(x, y);
  for (int y = 0; y < b.height(); ++y)
    for (int x = 0; x < b.width(); ++x) out.at(x, a.height() + 4 + y) = b.at(x, y);
  return out;
}

/// The runs grouped by (sweep, scene, point) ignoring the render.* axes (sample budget, ε),
/// which share a reference; groups in first-seen order.
struct Groups {
  std::map<std::string, std::vector<const RunRecord*>> runs;
  std::vector<std::string> order;
};

Groups groupRuns(const std::vector<RunRecord>& runs) {
  Groups g;
  for (const RunRecord& rec : runs) {
    std::string key = rec.sweep + "__" + rec.scene;
    for (const auto& [a, v] : rec.axes.items())
      if (a != "samples" && a != "epsilon" && a.rfind("render.", 0) != 0)
        key += "__" + fileSafe(a) + "-" + fileSafe(valueLabel(v));
    if (!g.runs.count(key)) g.order.push_back(key);
    g.runs[key].push_back(&rec);
  }
  return g;
}

/// Writes the strip of group `g` to `file` and appends its entry to `md`; nothing when it has
/// no image.
void writeStrip(std::ostream& md, const ExperimentPlan& plan, const std::string& g,
                const std::vector<const RunRecord*>& group, ReferenceCache& refs, OutputDir& out,
                const std::string& file) {
  std::vector<Image> imgs;
  std::vector<std::string> names;
  // The references of the group's first run, from the cache.
  const RunSpec* spec = nullptr;
  for (const RunSpec& r : plan.runs)
    if (r.id == group.front()->id) spec = &r;
  if (spec)
    for (const MethodSpec& ref : plan.references) {
      Reference& rc = refs.get(*spec, ref);
      if (rc.ok) {
        imgs.push_back(rc.image);
        names.push_back(ref.name + " (reference)");
      }
    }
  for (const RunRecord* rec : group)
    if (rec->status == "ok" && fs::exists(out.path("images/" + rec->id + ".exr"))) {
      imgs.push_back(readExr(out.path("images/" + rec->id + ".exr")));
      names.push_back(rec->methodName +
                      (rec->samples ? " (" + std::to_string(*rec->samples) + " samples)" : ""));
    }
  if (imgs.empty()) return;
  if (file.rfind("gallery/", 0) == 0) fs::create_directories(out.path("gallery"));
  // Error maps against the headline reference: the first image when it rendered.
  const bool errors = plan.gallery == "image+error" && !names.empty() &&
                      names.front() == plan.references.front().name + " (reference)";
  if (errors) {
    std::vector<Image> maps;
    for (const Image& i : imgs)
      maps.push_back(i.width() == imgs.front().width() && i.height() == imgs.front().height()
                         ? signedErrorMap(i, imgs.front(), plan.exposure)
                         : Image(i.width(), i.height()));
    writePng(twoRows(imgs, maps), out.path(file), plan.exposure);
  } else {
    writePng(sideBySide(imgs), out.path(file), plan.exposure);
  }
  std::string caption;
  for (const auto& n : names) caption += (caption.empty() ? "" : ", ") + n;
  md << "**" << g << "** — " << caption << "\n\n![" << g << "](" << file << ")\n\n";
}

}  // namespace

void writeGallery(std::ostream& md, const ExperimentPlan& plan, const std::vector<RunRecord>& runs,
                  ReferenceCache& refs, OutputDir& out, bool plotted) {
  if (plan.gallery == "off") return;
  if (plotted && fs::exists(out.path("gallery/index.json"))) {
    const Json g = readJsonFile(out.path("gallery/index.json"));
    const Json pages = g.value("pages", Json::array());
    int ok = 0;
    for (const RunRecord& rec : runs) ok += rec.status == "ok";
    md << "## Gallery\n\n"
       << g.value("runs", 0) << " of the " << ok << " successful runs on " << pages.size()
       << " page" << (pages.size() == 1 ? "" : "s") << " (" << g.value("per_page", 0)
       << " a page; runs without an image are left out). Each tile: the run's PNG (exposure "
       << plan.exposure << ") titled with scene, method, backend, sweep point, samples used, "
       << "relative L2 against `" << g.value("reference", "") << "` and median frame time; "
       << "beside it the signed difference of the two PNGs (mean over channels; red = brighter "
          "than the reference, blue = darker, full colour at ±"
       << fmt(g.value("diff_full", 0.0), "%g") << "; visibly wrong starts at " << kVisibleThreshold
       << ").\n\n";
    for (const Json& p : pages)
      md << "![" << p.get<std::string>() << "](gallery/" << p.get<std::string>() << ")\n\n";
    return;
  }
  md << "## Gallery\n\nEach strip: the reference(s), then the runs of that sweep point, left to "
        "right (PNG, exposure "
     << plan.exposure << ").";
  if (plan.gallery == "image+error")
    md << " Below each image its signed error against `" << plan.references.front().name
       << "` after the PNG transform (exposure 0): red = brighter than the reference, blue = "
          "darker, full colour at a mean channel difference of "
       << kErrorMapFull << " (visibly wrong starts at " << kVisibleThreshold << ").";
  md << "\n\n";
  const Groups groups = groupRuns(runs);
  for (const std::string& g : groups.order) {
    const std::string file =
        groups.order.size() == 1 ? "side_by_side.png" : "gallery/" + g + ".png";
    try {
      writeStrip(md, plan, g, groups.runs.at(g), refs, out, file);
    } catch (const std::exception& e) {
      md << "**" << g << "** — gallery strip failed: " << e.what() << "\n\n";
    }
  }
}

std::string plotScript() {
  if (const char* env = std::getenv("SCATTERLAB_PLOTS_SCRIPT")) return env;
  // <prefix>/bin/scatterlab -> <prefix>/share/scatterlab/plots.py; the build tree has the same
  // layout (experiment/CMakeLists.txt copies the script there).
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  return (exe.parent_path().parent_path() / "share" / "scatterlab" / "plots.py").string();
}

std::string makePlots(const ExperimentOptions& opt, const OutputDir& out) {
  if (!opt.plots) return "plots not requested (--no-plots)";
  const std::string script = plotScript();
  if (script.empty())
    return "plot script not found ($SCATTERLAB_PLOTS_SCRIPT, or share/scatterlab/plots.py beside "
           "the executable's bin/)";
  if (!fs::exists(script)) return "plot script '" + script + "' not found";
  const std::string py = findPlotPython();
  if (py.empty())
    return "no python3 with matplotlib found ($SCATTERLAB_PYTHON, python3 on the PATH, "
           "/usr/bin/python3; install python3-matplotlib, e.g. by scripts/setup.sh)";
  const std::string cmd =
      "'" + py + "' '" + script + "' '" + out.dir() + "' >> '" + out.path("log.txt") + "' 2>&1";
  if (std::system(cmd.c_str()) != 0) return "the plot script failed; see log.txt";
  return "";
}

}  // namespace detail

}  // namespace scatterlab
