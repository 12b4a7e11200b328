#pragma once
/// Internal to the experiment harness (included only by experiment/*.cpp; apps and tests use
/// experiment/experiment.h): what its source files share — text and file helpers, the output
/// directory with its log, the reference cache, the run loop's entry point and the facts that
/// both the tables and the report derive from the finished runs.

#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "experiment/experiment.h"

namespace scatterlab::detail {

// ---- Text and files (detail.cpp) -------------------------------------------------------------

/// `v` through snprintf with `format`.
std::string fmt(double v, const char* format = "%.4g");

/// The whole file; "" when it cannot be read (callers have checked it is readable).
std::string readText(const std::string& path);

/// The hash of a scene file and of every file it names (medium.density.file and .frames,
/// objects[i].file and each OBJ's `mtllib`s, resolved from the scene's directory): a run or
/// reference keyed by it is redone when a mesh, volume or model changes, not only the JSON.
/// A file that cannot be read hashes as "missing" (the run itself then reports it). With
/// `sets` (a run's overrides), the files are those of the scene after them: a file named only
/// through a sweep's or a method's `set` is hashed too (issue 37: editing it resumed stale
/// results, 258 % off). File hashes are cached by path, size and modification time.
std::string sceneHash(const std::string& sceneFile, const std::vector<std::string>& sets = {});

/// Writes atomically, so that an interrupted run never leaves a truncated table or record.
void writeText(const std::string& path, const std::string& text);

/// `s` with every character other than letters, digits, '-', '_' and '.' replaced by '_'.
std::string fileSafe(std::string s);

/// An axis value as tables and ids show it: "128", "800x600", "0.5".
std::string valueLabel(const Json& v);

/// `100 * v` through `format` with a "%", "—" when `v` is not finite (report.md's and
/// report.html's error columns).
std::string percent(double v, const char* format);

/// Local time as "YYYY-MM-DD HH:MM:SS".
std::string nowIso();

/// The output directory: creates runs/, images/ and references/, and appends time-stamped lines
/// to log.txt (appended to, so that resumed experiments keep their history).
class OutputDir {
 public:
  explicit OutputDir(const std::string& dir);
  const std::string& dir() const { return dir_; }
  /// `file` (relative to the directory) as a path.
  std::string path(const std::string& file) const;
  void log(const std::string& line);

 private:
  std::string dir_;
  std::ofstream log_;
};

// ---- References (references.cpp) -------------------------------------------------------------

struct Reference {
  std::string name;
  Image image;
  bool ok = false;
  std::string error;  ///< why it could not be rendered or read
  std::string file;   ///< its PNG relative to DIR (references/<name>-<hash>.png)
  /// A converged reference's check (MethodSpec::converge): null for others.
  Json check;
};

/// References, rendered once per distinct (scene, reference overrides, reference method) and
/// cached on disk under DIR/references/<name>-<hash>.exr, so that a resumed experiment and
/// every sample budget of a sweep point share one.
class ReferenceCache {
 public:
  /// `console`: where a rendered reference gets a line (nullptr: nowhere); `clearLine`: the
  /// progress bar is on, so such a line first erases it.
  ReferenceCache(const ExperimentPlan& plan, OutputDir& out, std::FILE* console, bool clearLine)
      : plan_(plan), out_(out), console_(console), clearLine_(clearLine) {}

  /// The reference `ref` of run `r`. `seed`: the image of a run that renders exactly the
  /// reference's configuration (same method, backend, settings and scene), used instead of
  /// rendering it once more. A failure is recorded in the returned Reference, not thrown.
  Reference& get(const RunSpec& r, const MethodSpec& ref, const RenderResult* seed = nullptr);

 private:
  void render(const RunSpec& r, const MethodSpec& ref, const RenderResult* seed, const Json& key,
              const std::string& base, Reference& rc);
  /// Renders `ref` at ½ voxel and ¼ voxel and keeps the ½-voxel image when the two differ by
  /// less than kReferenceTolerance, else the ¼-voxel one; the check goes into `check`.
  RenderResult renderConverged(const Scene& scene, const MethodSpec& ref, Json& check);

  const ExperimentPlan& plan_;
  OutputDir& out_;
  std::FILE* console_;
  bool clearLine_;
  std::map<std::string, Reference> cache_;
  std::set<std::string> warned_;  ///< ignored-key warnings already given
};

// ---- Run loop (run.cpp) ----------------------------------------------------------------------

/// How the runs measure peak host memory, chosen once: VmHWM after resetting it where the
/// kernel allows that (Linux >= 4.0), else the process's lifetime peak from getrusage.
struct MemoryMeasure {
  bool resettable = false;
  std::string method;  ///< in words, for the tables and the report
};
/// Tries the reset (which also starts the first measurement).
MemoryMeasure chooseMemoryMeasure();

/// Renders (or resumes from DIR/runs/) every run of res.plan in order, appending to res.runs
/// and counting into res.rendered / resumed / failed.
/// `selected[i]`: run i of the plan is rendered (or resumed) here; others are skipped (another
/// shard's). `machine`: machineFacts(), stored in every rendered record.
void runAll(ExperimentResult& res, OutputDir& out, ReferenceCache& refs, const MemoryMeasure& mem,
            const ExperimentOptions& opt, bool progressBar, const std::vector<char>& selected,
            const Json& machine);

/// DIR/shard-K-of-N.json, written by a shard when its slice is done (shard.cpp): the config's
/// absolute path, the overrides, K, N, the plan's hash, the slice's run ids, the counts and the
/// machine; `scatterlab experiment merge` checks and joins them.
void writeShardManifest(const ExperimentResult& res, const std::string& configPath,
                        const ExperimentOptions& opt, const std::vector<char>& selected,
                        OutputDir& out);

/// The scene every reference of run `r` sees (scene file bytes, reference overrides, lights),
/// hashed: runs with the same group share their reference images.
std::string referenceGroup(const RunSpec& r);

// ---- Tables (tables.cpp) ---------------------------------------------------------------------

/// What the tables and the report derive from the finished runs.
struct ResultFacts {
  ResultFacts(const ExperimentPlan& plan, const std::vector<RunRecord>& runs);

  const ExperimentPlan& plan;
  const std::vector<RunRecord>& runs;
  std::vector<std::string> stages;     ///< union over the runs, first-seen order, no "total"
  std::vector<std::string> axisNames;  ///< union over the runs, first-seen order
  /// The distinct machines the runs were rendered on (host, CPU model, cores used, commit), in
  /// first-seen order: those facts, the load average at the start of the first of its runs,
  /// `gpu_renderers` (the GL renderers of its GPU runs) and `runs` (how many). Runs resumed
  /// from records older than the machine facts count under an empty machine.
  Json machines = Json::array();

  /// The median of `stage` in `rec`; none when the run has no such stage.
  static std::optional<double> stageMs(const RunRecord& rec, const std::string& stage);
  /// The run `rec`'s speed-up is measured against (nullptr: none).
  const RunRecord* baselineOf(const RunRecord& rec) const;
  /// The slowest stage with its share of the total, e.g. "march (61%)"; "" without stages.
  static std::string dominantStage(const RunRecord& rec);
};

/// A paper value of a record formatted with `format`; "" when the config gave none.
std::string paperValue(const Json& paper, const char* key, const char* format);

/// The distinct convergence checks of the converged references (one per reference image), each
/// with the reference, scene, sweep and the first run that used it.
Json referenceChecks(const ResultFacts& facts);

/// results.csv: one row per run.
std::string resultsCsv(const ResultFacts& facts);
/// results.json: the records plus what the CSV derives (fps, speed-up, dominant stage).
Json resultsJson(const ResultFacts& facts, const ExperimentResult& res,
                 const std::string& configPath, const std::string& memoryMethod);

// ---- Report (report.cpp) ---------------------------------------------------------------------

/// One machine of ResultFacts::machines in words: CPU, cores used, load at the start, GPU
/// renderer, host, OS, commit.
std::string machineLine(const Json& machine);

/// report.md's title, summary and conventions.
void reportHeader(std::ostream& md, const ExperimentResult& res, const std::string& configPath,
                  const std::string& memoryMethod);
/// One sweep's results table and per-stage breakdown.
void reportSweep(std::ostream& md, const ResultFacts& facts, const SweepSpec& sweep);
/// The convergence checks of the converged references; nothing when there are none.
void reportReferenceChecks(std::ostream& md, const ResultFacts& facts);
/// The plots with their captions (DIR/plots/index.json, written by plots.py) or why there are
/// none.
void reportPlots(std::ostream& md, const std::string& plotsNote, OutputDir& out);
/// The failed runs with their configurations; nothing when none failed.
void reportFailures(std::ostream& md, const ExperimentResult& res);

// ---- report.html (report_html.cpp) -----------------------------------------------------------

/// The bytes of experiment/report_html/<name> (template.html, viewer.css, viewer.js), compiled in
/// by cmake/embed_files.cmake; empty for another name.
std::string_view embeddedFile(std::string_view name);

/// The integer box-filter factor that brings the longer side of a width × height image to at
/// most `maxSide` pixels (1: no downscaling).
int boxFactor(int width, int height, int maxSide);
/// `img` box-filtered by `factor`: each pixel the mean of a factor × factor block (the blocks
/// at the right and bottom edges average the pixels they cover).
Image boxDownscale(const Image& img, int factor);

/// DIR/report.html: one page with no outside references — a viewer per reference scene (the
/// references and every run measured against them, as deflated half-float RGB, downscaled by
/// boxFactor(plan.htmlMaxSide) with the EXR linked), the metrics table with report.md's numbers,
/// the plots (inline PNGs with captions), the machines and commits. An image that cannot be read
/// is left out and named in the page and log.txt.
void writeReportHtml(const ExperimentResult& res, const ResultFacts& facts,
                     const std::string& configPath, const std::string& memoryMethod,
                     OutputDir& out);

// ---- Gallery and plots (gallery.cpp) ---------------------------------------------------------

/// The gallery's 5×7 bitmap font (also the labels of error_map.cpp's colour scale): the pixel
/// width of `text` at `scale` (6·scale a character, the last one's gap dropped) ...
int textWidth(const std::string& text, int scale);
/// ... `text` drawn with its top left corner at (x0, y0), each font pixel a `scale`² block of
/// value `c` (lower case as capitals, other characters as '?'; clipped) ...
void drawText(Image& img, int x0, int y0, const std::string& text, int scale, const Vec3& c);
/// ... and the font scale for a panel `width` pixels wide: 1 up to 259 px, 2 up to 389, at most 3.
int labelScale(int width);

/// Appends the gallery section to `md`: the labelled pages plots.py wrote (DIR/gallery/
/// page-NN.png, listed in gallery/index.json) when `plotted`; otherwise (no python with
/// matplotlib, --no-plots) one unlabelled side-by-side strip per (sweep, scene, point), the
/// references then every run, captioned with their names.
void writeGallery(std::ostream& md, const ExperimentPlan& plan, const std::vector<RunRecord>& runs,
                  ReferenceCache& refs, OutputDir& out, bool plotted);

/// The plot script: $SCATTERLAB_PLOTS_SCRIPT, else <dir of the executable>/../share/scatterlab/
/// plots.py (the build tree and an installed prefix have that layout); "" when neither is known.
std::string plotScript();

/// Calls experiment/plots.py on the output directory (when `opt.plots`); returns why there are
/// no plots, or "" when they were made.
std::string makePlots(const ExperimentOptions& opt, const OutputDir& out);

}  // namespace scatterlab::detail
