// The experiment's pictures: side-by-side strips of the references and the runs of each sweep
// point (report.md's gallery), and the plots made by experiment/plots.py.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>

#include "core/scene.h"
#include "experiment/detail.h"
#include "experiment/error_map.h"

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

// ---- Labels: a 5×7 bitmap font of capitals, digits and the punctuation of the labels ----------

struct Glyph {
  char c;
  std::uint8_t rows[7];  ///< top to bottom, bit 4 = the leftmost of 5 columns
};

constexpr Glyph kGlyphs[] = {
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
    {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
    {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},
    {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},
    {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},
    {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},
    {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x0A, 0x04, 0x04, 0x04, 0x04}},
    {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},
    {'?', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04}},
};

const Glyph* glyphOf(char c) {
  if (c >= 'a' && c <= 'z') c = char(c - 'a' + 'A');
  for (const Glyph& g : kGlyphs)
    if (g.c == c) return &g;
  return nullptr;
}

}  // namespace

/// Pixel width of `text` at `scale` (6·scale a character, the last one's gap dropped).
int textWidth(const std::string& text, int scale) {
  return text.empty() ? 0 : int(text.size()) * 6 * scale - scale;
}

/// Draws `text` with its top left corner at (x0, y0), each font pixel a `scale`² block of
/// value `c`; lower case as capitals, other characters as '?' (a space as nothing); clipped.
void drawText(Image& img, int x0, int y0, const std::string& text, int scale, const Vec3& c) {
  for (std::size_t k = 0; k < text.size(); ++k) {
    if (text[k] == ' ') continue;
    const Glyph* g = glyphOf(text[k]);
    if (!g) g = glyphOf('?');
    for (int row = 0; row < 7; ++row)
      for (int col = 0; col < 5; ++col) {
        if (!(g->rows[row] >> (4 - col) & 1)) continue;
        for (int dy = 0; dy < scale; ++dy)
          for (int dx = 0; dx < scale; ++dx) {
            const int x = x0 + int(k) * 6 * scale + col * scale + dx, y = y0 + row * scale + dy;
            if (x >= 0 && y >= 0 && x < img.width() && y < img.height()) img.at(x, y) = c;
          }
      }
  }
}

/// Font scale for a panel `width` pixels wide: 1 up to 259 px, 2 up to 389, at most 3.
int labelScale(int width) {
  return std::clamp(width / 130, 1, 3);
}

namespace {

/// `lines` wrapped at spaces to at most `maxChars` characters a line (a longer word is cut).
std::vector<std::string> wrapLines(const std::vector<std::string>& lines, int maxChars) {
  std::vector<std::string> out;
  maxChars = std::max(1, maxChars);
  for (const std::string& line : lines) {
    std::string cur;
    std::size_t i = 0;
    while (i <= line.size()) {
      const std::size_t j = std::min(line.find(' ', i), line.size());
      std::string word = line.substr(i, j - i);
      while (int(word.size()) > maxChars) {  // a word longer than a line: cut it
        if (!cur.empty()) out.push_back(cur), cur.clear();
        out.push_back(word.substr(0, std::size_t(maxChars)));
        word = word.substr(std::size_t(maxChars));
      }
      if (!cur.empty() && int(cur.size() + 1 + word.size()) > maxChars)
        out.push_back(cur), cur.clear();
      if (!word.empty()) cur += (cur.empty() ? "" : " ") + word;
      i = j + 1;
    }
    if (!cur.empty()) out.push_back(cur);
  }
  return out;
}

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

/// Each image under a black band holding its label lines (white capitals, wrapped to its width;
/// one font scale and band height for the whole strip).
std::vector<Image> labelled(const std::vector<StripPanel>& panels, float exposure) {
  int minW = 1 << 30;
  for (const StripPanel& p : panels) minW = std::min(minW, p.image.width());
  const int scale = labelScale(minW);
  std::vector<std::vector<std::string>> lines;
  std::size_t most = 0;
  for (const StripPanel& p : panels) {
    lines.push_back(wrapLines(p.label, (p.image.width() + scale) / (6 * scale)));
    most = std::max(most, lines.back().size());
  }
  const int band = most ? int(most) * 9 * scale + 2 * scale : 0;
  const float white = std::exp2(-exposure);
  std::vector<Image> out;
  for (std::size_t k = 0; k < panels.size(); ++k) {
    const Image& img = panels[k].image;
    Image o(img.width(), img.height() + band);
    for (std::size_t l = 0; l < lines[k].size(); ++l)
      drawText(o, 0, 2 * scale + int(l) * 9 * scale, lines[k][l], scale, Vec3(white, white, white));
    for (int y = 0; y < img.height(); ++y)
      for (int x = 0; x < img.width(); ++x) o.at(x, band + y) = img.at(x, y);
    out.push_back(std::move(o));
  }
  return out;
}

/// ", 379 ms": the render time of reference `rc` from the stats cached beside it (one render,
/// not a median); "" where they are missing.
std::string referenceTime(const OutputDir& out, const Reference& rc) {
  if (rc.file.empty()) return "";
  const fs::path stats = fs::path(out.path(rc.file)).replace_extension(".json");
  try {
    if (!fs::exists(stats)) return "";
    const Json t = readJsonFile(stats.string()).value("timings_ms", Json::object());
    if (t.contains("total") && t["total"].is_number())
      return ", " + fmt(t["total"].get<double>(), "%.0f") + " ms";
  } catch (const std::exception&) {
  }
  return "";
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
  std::vector<StripPanel> panels;
  std::vector<std::string> names;
  const std::string& head = plan.references.front().name;
  // The references of the group's first run, from the cache.
  const RunSpec* spec = nullptr;
  for (const RunSpec& r : plan.runs)
    if (r.id == group.front()->id) spec = &r;
  if (spec)
    for (const MethodSpec& ref : plan.references) {
      Reference& rc = refs.get(*spec, ref);
      if (!rc.ok) continue;
      const bool headline = &ref == &plan.references.front();
      StripPanel p{rc.image, {ref.name, headline ? "reference" : "reference 2"}};
      p.label[1] += referenceTime(out, rc);
      if (!headline) {
        // A second reference (per-voxel beside exact): a baseline, with its error against the
        // headline one when that rendered.
        if (!panels.empty() && names.front() == head + " (reference)" &&
            panels.front().image.width() == rc.image.width() &&
            panels.front().image.height() == rc.image.height())
          p.label.push_back(
              "rel L2 " + fmt(100.0 * compareImages(rc.image, panels.front().image).relL2, "%.2f") +
              "%");
      }
      panels.push_back(std::move(p));
      names.push_back(ref.name + " (reference)");
    }
  for (const RunRecord* rec : group)
    if (rec->status == "ok" && fs::exists(out.path("images/" + rec->id + ".exr"))) {
      StripPanel p{readExr(out.path("images/" + rec->id + ".exr")), {rec->methodName}};
      std::string second = rec->samples ? std::to_string(*rec->samples) + " samples, " : "";
      p.label.push_back(second + fmt(rec->totalMs(), "%.0f") + " ms");
      if (!rec->errors.empty() && !std::isnan(rec->errors[0].relL2))
        p.label.push_back("rel L2 " + fmt(100.0 * rec->errors[0].relL2, "%.2f") + "%");
      for (const auto& [a, v] : rec->axes.items()) p.label.push_back(a + "=" + valueLabel(v));
      panels.push_back(std::move(p));
      names.push_back(rec->methodName +
                      (rec->samples ? " (" + std::to_string(*rec->samples) + " samples)" : ""));
    }
  if (panels.empty()) return;
  if (file.rfind("gallery/", 0) == 0) fs::create_directories(out.path("gallery"));
  // Error maps against the headline reference: the first image when it rendered.
  const bool errors = plan.gallery == "image+error" && names.front() == head + " (reference)";
  writePng(galleryStrip(panels, errors, plan.exposure), out.path(file), plan.exposure);
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
     << plan.exposure
     << "), each labelled above in the image: a run with its method, samples used, median "
        "frame time, relative L2 against `"
     << plan.references.front().name
     << "` and its sweep point; a reference with its name and render time (one render; a second "
        "reference with its relative L2 against the first).";
  if (plan.gallery == "image+error")
    md << " Below each image its signed error against `" << plan.references.front().name
       << "` after the PNG transform (exposure 0): red = brighter than the reference, blue = "
          "darker, full colour at a mean channel difference of "
       << kErrorMapFull << " (visibly wrong starts at " << kVisibleThreshold
       << "); below the reference itself, whose error is 0 everywhere, the colour scale of "
          "those maps (−"
       << kErrorMapFull << " blue at the left, 0 black, +" << kErrorMapFull
       << " red at the right).";
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

Image galleryStrip(const std::vector<StripPanel>& panels, bool errors, float exposure) {
  if (panels.empty()) return Image();
  const std::vector<Image> top = detail::labelled(panels, exposure);
  if (!errors) return detail::sideBySide(top);
  const Image& ref = panels.front().image;
  std::vector<Image> maps{errorScale(ref.width(), ref.height(), exposure)};
  for (std::size_t k = 1; k < panels.size(); ++k) {
    const Image& i = panels[k].image;
    maps.push_back(i.width() == ref.width() && i.height() == ref.height()
                       ? signedErrorMap(i, ref, exposure)
                       : Image(i.width(), i.height()));
  }
  return detail::twoRows(top, maps);
}

}  // namespace scatterlab
