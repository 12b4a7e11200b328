// The experiment's report.html: one self-contained page (the template, style and script of
// experiment/report_html/ compiled in, every image and plot inline) with a viewer per reference
// scene — the images as deflated half floats that the page tone-maps itself —, the sortable
// metrics table, the plots and the machine.

#include <Imath/half.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "core/error.h"
#include "experiment/detail.h"

namespace scatterlab::detail {

namespace fs = std::filesystem;

namespace {

std::string base64(const unsigned char* p, std::size_t n) {
  static constexpr char kDigits[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  for (std::size_t i = 0; i < n; i += 3) {
    const unsigned v = unsigned(p[i]) << 16 | (i + 1 < n ? unsigned(p[i + 1]) << 8 : 0u) |
                       (i + 2 < n ? unsigned(p[i + 2]) : 0u);
    out += kDigits[v >> 18 & 63];
    out += kDigits[v >> 12 & 63];
    out += i + 1 < n ? kDigits[v >> 6 & 63] : '=';
    out += i + 2 < n ? kDigits[v & 63] : '=';
  }
  return out;
}

/// zlib-wrapped deflate, the format the page's DecompressionStream("deflate") reads.
std::vector<unsigned char> deflateBytes(const std::vector<unsigned char>& in) {
  uLongf n = compressBound(uLong(in.size()));
  std::vector<unsigned char> out(n);
  if (compress2(out.data(), &n, in.data(), uLong(in.size()), Z_BEST_COMPRESSION) != Z_OK)
    throw Error("report.html: zlib could not compress an image of " + std::to_string(in.size()) +
                " bytes");
  out.resize(n);
  return out;
}

/// The image in the page's encoding: RGB half floats (Imath::half, round to nearest), pixel
/// after pixel from the top row; as bytes the low byte of every half, then every high byte
/// (byte planes deflate about a third smaller than interleaved halves); deflated; base64.
std::string encodeImage(const Image& img) {
  const std::size_t n = img.pixels().size() * 3;
  std::vector<unsigned char> bytes(2 * n);
  for (std::size_t i = 0; i < img.pixels().size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const unsigned short bits = Imath::half(img.pixels()[i][c]).bits();
      bytes[3 * i + c] = static_cast<unsigned char>(bits & 0xff);
      bytes[n + 3 * i + c] = static_cast<unsigned char>(bits >> 8);
    }
  const std::vector<unsigned char> packed = deflateBytes(bytes);
  return base64(packed.data(), packed.size());
}

std::string htmlEscape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

/// JSON that may stand inside a <script> element: every '<' (which JSON has only inside strings)
/// becomes \u003c, so that neither "</script>" nor "<!--" can occur.
std::string scriptSafe(const std::string& json) {
  std::string o;
  o.reserve(json.size());
  for (char c : json) {
    if (c == '<')
      o += "\\u003c";
    else
      o += c;
  }
  return o;
}

/// `text` with every {{name}} replaced by parts[name]; an unknown name is a build defect.
std::string fillTemplate(std::string_view text, const std::map<std::string, std::string>& parts) {
  std::string o;
  std::size_t at = 0;
  while (true) {
    const std::size_t open = text.find("{{", at);
    if (open == std::string_view::npos) break;
    const std::size_t close = text.find("}}", open);
    if (close == std::string_view::npos) break;
    const std::string name(text.substr(open + 2, close - open - 2));
    const auto it = parts.find(name);
    if (it == parts.end())
      throw Error("report.html template: unknown placeholder {{" + name + "}}");
    o.append(text.substr(at, open - at));
    o += it->second;
    at = close + 2;
  }
  o.append(text.substr(at));
  return o;
}

std::string asset(const char* name) {
  const std::string_view s = embeddedFile(name);
  if (s.empty())
    throw Error(std::string("report.html: the embedded asset ") + name + " is missing");
  return std::string(s);
}

bool isRenderAxis(const std::string& a) {
  return a == "samples" || a == "epsilon" || a.rfind("render.", 0) == 0;
}

/// The page's images, each stored once (a reference serves several viewers), and its notes.
class PageImages {
 public:
  PageImages(OutputDir& out, int maxSide) : out_(out), maxSide_(maxSide) {}

  /// The index of the EXR `exr` (relative to DIR) in the page, -1 when it cannot be read (the
  /// reason goes to missing()).
  int add(const std::string& exr) {
    if (const auto it = index_.find(exr); it != index_.end()) return it->second;
    Image img;
    try {
      img = readExr(out_.path(exr));
    } catch (const std::exception& e) {
      missing_.push_back(exr + ": " + e.what());
      return index_[exr] = -1;
    }
    const int factor = boxFactor(img.width(), img.height(), maxSide_);
    const Image shown = factor > 1 ? boxDownscale(img, factor) : img;
    const int k = int(meta_.size());
    meta_.push_back({{"exr", exr},
                     {"w", shown.width()},
                     {"h", shown.height()},
                     {"full_w", img.width()},
                     {"full_h", img.height()},
                     {"factor", factor},
                     {"data", "img-" + std::to_string(k)}});
    data_ += "<script type=\"application/octet-stream\" id=\"img-" + std::to_string(k) + "\">" +
             encodeImage(shown) + "</script>\n";
    return index_[exr] = k;
  }

  const Json& meta() const { return meta_; }
  const std::string& data() const { return data_; }
  const std::vector<std::string>& missing() const { return missing_; }

 private:
  OutputDir& out_;
  int maxSide_;
  std::map<std::string, int> index_;
  Json meta_ = Json::array();
  std::string data_;
  std::vector<std::string> missing_;
};

/// The images of one reference scene: the references then the runs that were measured
/// against them.
struct Group {
  std::vector<std::string> refs;  ///< EXRs of the references, in plan order
  std::vector<const RunRecord*> runs;
};

Json tableCell(const std::string& text, const Json& sortValue) {
  return {{"t", text}, {"v", sortValue}};
}

Json finiteOrNull(double v) {
  return std::isfinite(v) ? Json(v) : Json(nullptr);
}

}  // namespace

int boxFactor(int width, int height, int maxSide) {
  const int side = std::max(width, height);
  return side <= maxSide ? 1 : (side + maxSide - 1) / maxSide;
}

Image boxDownscale(const Image& img, int factor) {
  Image out((img.width() + factor - 1) / factor, (img.height() + factor - 1) / factor);
  for (int y = 0; y < out.height(); ++y)
    for (int x = 0; x < out.width(); ++x) {
      Vec3 sum(0.0f);
      int n = 0;
      for (int v = y * factor; v < std::min(img.height(), (y + 1) * factor); ++v)
        for (int u = x * factor; u < std::min(img.width(), (x + 1) * factor); ++u) {
          sum += img.at(u, v);
          ++n;
        }
      out.at(x, y) = sum / float(n);
    }
  return out;
}

void writeReportHtml(const ExperimentResult& res, const ResultFacts& facts,
                     const std::string& configPath, const std::string& memoryMethod,
                     OutputDir& out) {
  const ExperimentPlan& plan = res.plan;
  PageImages images(out, plan.htmlMaxSide);

  // Viewers: the successful runs grouped by the reference images they were measured against.
  std::vector<Group> groups;
  std::map<std::string, std::size_t> groupOf;          // references' EXRs joined -> index
  std::map<std::string, std::pair<int, int>> runItem;  // run id -> (group, item)
  for (const RunRecord& rec : facts.runs) {
    if (rec.status != "ok") continue;
    Group g;
    std::string key;
    for (const MethodSpec& ref : plan.references) {
      const std::string png = rec.referenceImages.value(ref.name, "");
      if (png.empty()) continue;
      g.refs.push_back(fs::path(png).replace_extension(".exr").string());
      key += g.refs.back() + "\n";
    }
    const auto [it, fresh] = groupOf.emplace(key, groups.size());
    if (fresh) groups.push_back(g);
    groups[it->second].runs.push_back(&rec);
  }
  Json jgroups = Json::array();
  for (std::size_t gi = 0; gi < groups.size(); ++gi) {
    const Group& g = groups[gi];
    const RunRecord& first = *g.runs.front();
    // Title: what the group shares; labels: what tells its runs apart.
    std::string title = "scene " + first.scene;
    std::set<std::string> sweeps;
    std::vector<std::string> varying;
    for (const RunRecord* r : g.runs) sweeps.insert(r->sweep);
    for (const std::string& a : facts.axisNames) {
      std::set<std::string> vals;
      for (const RunRecord* r : g.runs)
        vals.insert(r->axes.contains(a) ? valueLabel(r->axes[a]) : "");
      if (vals.size() > 1 || isRenderAxis(a))
        varying.push_back(a);
      else if (!vals.begin()->empty())
        title += ", " + a + " " + *vals.begin();
    }
    if (sweeps.size() == 1 && plan.sweeps.size() > 1) title = "sweep " + first.sweep + ", " + title;
    Json items = Json::array();
    for (std::size_t k = 0; k < g.refs.size(); ++k) {
      const int img = images.add(g.refs[k]);
      if (img >= 0)
        items.push_back({{"image", img},
                         {"label", plan.references[k].name + " (reference)"},
                         {"kind", "reference"},
                         {"png", fs::path(g.refs[k]).replace_extension(".png").string()}});
    }
    const int nRefs = int(items.size());
    for (const RunRecord* r : g.runs) {
      const int img = images.add("images/" + r->id + ".exr");
      if (img < 0) continue;
      std::string label = r->methodName;
      if (r->backend != "cpu") label += " (" + r->backend + ")";
      if (sweeps.size() > 1) label = r->sweep + ": " + label;
      for (const std::string& a : varying)
        if (r->axes.contains(a)) label += ", " + a + " " + valueLabel(r->axes[a]);
      runItem[r->id] = {int(gi), int(items.size())};
      items.push_back(
          {{"image", img}, {"label", label}, {"kind", "run"}, {"run", r->id}, {"png", r->image}});
    }
    if (items.empty()) continue;
    jgroups.push_back({{"title", title}, {"items", items}, {"reference", nRefs > 0 ? 0 : -1}});
  }

  // The metrics table: the numbers of report.md's sweep tables, one row per run.
  const std::string& head = plan.references[0].name;
  Json columns = Json::array({"run", "sweep", "scene", "method", "backend"});
  for (const std::string& a : facts.axisNames)
    columns.push_back(a == "samples" ? "sample budget" : a);
  for (const char* c : {"samples used", "time (ms)", "fps"}) columns.push_back(c);
  columns.push_back("rel L2 vs " + head);
  for (const char* c : {"masked rel L2 (K px)", "rel L1", "visibly wrong"}) columns.push_back(c);
  columns.push_back("overrides (--set)");
  Json rows = Json::array();
  for (const RunRecord& rec : facts.runs) {
    Json cells =
        Json::array({tableCell(rec.id, rec.id), tableCell(rec.sweep, rec.sweep),
                     tableCell(rec.scene, rec.scene), tableCell(rec.methodName, rec.methodName),
                     tableCell(rec.backend, rec.backend)});
    // An axis value sorts as a number where it is one ([w, h] image sizes as text); a run
    // without the axis last.
    for (const std::string& a : facts.axisNames) {
      const Json v = rec.axes.value(a, Json());
      if (v.is_null())
        cells.push_back(tableCell("", nullptr));
      else
        cells.push_back(tableCell(valueLabel(v), v.is_number() ? v : Json(valueLabel(v))));
    }
    const bool ok = rec.status == "ok";
    Json row = {{"run", rec.id}, {"ok", ok}};
    if (!ok) {
      row["error"] = rec.error;
      row["status"] = rec.status;
    } else {
      cells.push_back(rec.samples ? tableCell(rec.samplesLabel(), *rec.samples)
                                  : tableCell(rec.samplesLabel(), nullptr));
      cells.push_back(tableCell(fmt(rec.totalMs(), "%.1f"), rec.totalMs()));
      const double fps = 1000.0 / std::max(rec.totalMs(), 1e-9);
      cells.push_back(tableCell(fmt(fps, "%.2f"), fps));
      if (!rec.errors.empty()) {
        const ImageError& e = rec.errors[0];
        cells.push_back(tableCell(percent(e.relL2, "%.2f"), finiteOrNull(e.relL2)));
        cells.push_back(tableCell(
            percent(e.maskedRelL2, "%.2f") +
                (std::isfinite(e.maskRadius) ? " (" + fmt(e.maskRadius, "%.3g") + ")" : ""),
            finiteOrNull(e.maskedRelL2)));
        cells.push_back(tableCell(percent(e.relL1, "%.2f"), finiteOrNull(e.relL1)));
        cells.push_back(tableCell(percent(e.visiblyWrong, "%.3f"), finiteOrNull(e.visiblyWrong)));
      } else {
        for (int k = 0; k < 4; ++k) cells.push_back(tableCell("—", nullptr));
      }
      // The --set overrides the run was rendered with (the config's, then the method's).
      std::string sets;
      for (const Json& s : rec.config.value("sets", Json::array()))
        if (s.is_string()) sets += (sets.empty() ? "" : " ") + s.get<std::string>();
      cells.push_back(tableCell(sets, sets));
      if (const auto it = runItem.find(rec.id); it != runItem.end()) {
        row["group"] = it->second.first;
        row["item"] = it->second.second;
      }
    }
    row["cells"] = cells;
    rows.push_back(row);
  }

  // The plots, inline, with their captions (plots/index.json, written by plots.py).
  Json plots = Json::array();
  std::string plotsNote = res.plotsNote;
  if (plotsNote.empty() && fs::exists(out.path("plots/index.json"))) {
    for (const Json& p : readJsonFile(out.path("plots/index.json"))) {
      const std::string file = "plots/" + p.value("file", "");
      const std::string png = readText(out.path(file));
      if (png.empty()) {
        plots.push_back({{"caption", p.value("caption", "")}, {"missing", file}});
        continue;
      }
      plots.push_back(
          {{"caption", p.value("caption", "")},
           {"src", "data:image/png;base64," +
                       base64(reinterpret_cast<const unsigned char*>(png.data()), png.size())},
           {"svg", "plots/" + p.value("svg", "")}});
    }
  } else if (plotsNote.empty()) {
    plotsNote = "no plots/index.json";
  }

  Json machines = Json::array();
  for (const Json& m : facts.machines) machines.push_back(machineLine(m));
  Json failures = Json::array();
  for (const RunRecord& rec : res.runs)
    if (rec.status != "ok")
      failures.push_back({{"run", rec.id}, {"error", rec.error}, {"status", rec.status}});
  const Json data = {{"title", plan.title},
                     {"description", plan.description},
                     {"config", configPath},
                     {"written", nowIso()},
                     {"runs", res.runs.size()},
                     {"rendered", res.rendered},
                     {"resumed", res.resumed},
                     {"failed", res.failed},
                     {"refused", res.refused},
                     {"reference", head},
                     {"memory_method", memoryMethod},
                     {"machines", machines},
                     {"max_side", plan.htmlMaxSide},
                     // What the PNGs beside the EXRs show (writePng: linear curve, this exposure):
                     // the viewers' default.
                     {"png_tone", "linear"},
                     {"png_exposure", plan.exposure},
                     {"images", images.meta()},
                     {"groups", jgroups},
                     {"table", {{"columns", columns}, {"rows", rows}}},
                     {"plots", plots},
                     {"plots_note", plotsNote},
                     {"missing", images.missing()},
                     {"failures", failures}};
  for (const std::string& m : images.missing()) out.log("report.html: image left out: " + m);
  const std::string page =
      fillTemplate(asset("template.html"),
                   {{"title", htmlEscape(plan.title)},
                    {"style", asset("viewer.css")},
                    {"script", asset("viewer.js")},
                    {"data", scriptSafe(data.dump(-1, ' ', false, Json::error_handler_t::replace))},
                    {"images", images.data()}});
  writeText(out.path("report.html"), page);
  out.log("report.html: " + std::to_string(images.meta().size()) + " images, " +
          fmt(double(page.size()) / (1024.0 * 1024.0), "%.2f") + " MiB");
}

}  // namespace scatterlab::detail
