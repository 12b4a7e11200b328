#pragma once
/// The experiment harness behind `scatterlab experiment CONFIG.json -o DIR` (issue 7): scenes ×
/// methods (with backend) × parameter sweeps, errors against a cached reference, per-stage
/// times as the median of K repetitions after a warm-up, peak host memory, sample counts;
/// results.csv, results.json, report.md, report.html, images, plots. Resumable: every finished run
/// leaves DIR/runs/<id>.json (written atomically, keyed by a hash of its configuration) and is not
/// rendered again while that record exists and its hash matches.
///
/// The config format is documented key by key in docs/harness.md. Strict: unknown keys are
/// ConfigErrors naming the dotted key.

#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/method.h"
#include "core/params.h"

namespace scatterlab {

/// A method as configured (a run's method or a reference).
struct MethodSpec {
  std::string name;     ///< label in tables and file names
  std::string method;   ///< registered method name
  std::string backend;  ///< "cpu", "gpu" or "auto"
  std::vector<std::string> sets;
  Json paper = Json::object();  ///< paper values copied into the results (e.g. rel_error)
  /// References only: render with march_step = delta1 = ½ voxel of the run's scene, and check
  /// that halving both again moves the image by < kReferenceTolerance relative L2, else use
  /// the ¼-voxel image (one refinement) and record that. The default reference is `exact`
  /// with this on (docs/metrics.md).
  bool converge = false;
};

/// The largest relative L2 change a converged reference may show when its steps are halved.
inline constexpr double kReferenceTolerance = 0.005;

struct SceneSpec {
  std::string name, file;  ///< file: absolute or relative to the working directory
  std::vector<std::string> sets;
};

/// One axis value: a label for tables ("128", "800x600") and what it does to the scene.
struct AxisValue {
  Json value;
  std::vector<std::string> sets;  ///< scene overrides
  std::optional<int> lights;      ///< replicate the first light on a ring into this many
  bool affectsReference = true;   ///< false for render.* keys (sample budget, ε): shared reference
};

struct Axis {
  std::string name;
  std::vector<AxisValue> values;
};

struct SweepSpec {
  std::string name;
  std::vector<Axis> axes;            ///< the cartesian product of their values
  std::vector<std::string> methods;  ///< names of MethodSpecs (all when the config gives none)
  std::vector<std::string> scenes;   ///< names of SceneSpecs (all when none)
  int repetitions = 3, warmup = 1;
  /// Steady frames per run after the cold repetitions (0: none): the run's method kept between
  /// renders as a Renderer keeps it, light 0 moved a little each frame, the image left on the
  /// device (what an engine draws; docs/harness.md).
  int steadyFrames = 0;
  std::string baseline;  ///< method name that speed-ups are measured against ("" = none)
  /// method name -> paper value per sweep point (in product order), e.g. Table 2's fps.
  Json paperFps = Json::object();
};

/// One planned render: a scene, a method and one point of a sweep.
struct RunSpec {
  std::string id;  ///< unique, file-name safe
  std::string sweep, scene, method;
  const MethodSpec* spec = nullptr;
  const SceneSpec* sceneSpec = nullptr;
  const SweepSpec* sweepSpec = nullptr;
  int point = 0;                  ///< index of the sweep point (product order)
  Json axes = Json::object();     ///< axis name -> value
  std::vector<std::string> sets;  ///< all scene overrides, in order
  std::optional<int> lights;
  std::vector<std::string> refSets;  ///< the overrides the reference of this run uses
  std::optional<int> refLights;
  bool axesAllAffectReference = true;  ///< no render.* axis: the reference sees the same scene
  std::string hash;                    ///< of everything that determines the result
  Json paperFps;                       ///< null when the config gives none
};

struct ExperimentPlan {
  std::string title, description;
  std::vector<SceneSpec> scenes;
  std::vector<MethodSpec> references;  ///< the first is the headline reference
  bool defaultReference = false;       ///< the config named none: `exact`, converged
  std::vector<MethodSpec> methods;
  std::vector<SweepSpec> sweeps;
  float exposure = 0.0f;
  /// Radius in pixels of the disc masked around each light for the masked relative L2; none:
  /// defaultMaskRadius() of each image (1 % of its diagonal, at least 2 px).
  std::optional<double> maskRadius;
  /// Gallery strips: "images" (references, then runs), "image+error" (a second row with each
  /// image's signed error map against the headline reference) or "off".
  std::string gallery = "images";
  /// report.html shows images whose longer side exceeds this box-filtered by the smallest
  /// integer factor that brings it within (the EXRs linked at full size).
  int htmlMaxSide = 512;
  std::vector<RunSpec> runs;
};

/// Parses and validates a config (ConfigError naming the key; IoError for missing files) and
/// expands it into runs. `overrides` (the command line's --set) apply to every render.
ExperimentPlan parseExperiment(const std::string& configPath,
                               const std::vector<std::string>& overrides = {});

/// The `lights` sweep axis's lights (docs/harness.md): `first` (a scene's first light, as JSON)
/// replicated on a ring of `n` lights around the box centre `centre`, rotated about +Y (its
/// position about the centre, a direction with it), each with 1/n of its power (intensity or
/// irradiance), so the total stays the same; n = 1 is `first` itself. The GPU report's frames
/// (bench/bench_gpu.cpp) use the same ring, so that their frames and the harness's are the same
/// scenes at every light count.
Json ringOfLights(const Json& first, Vec3 centre, int n);

/// Builds the scene of a run: the scene file, `sets` in order, then the first light replicated
/// on a ring into `lights` lights (ringOfLights) when given.
Scene buildRunScene(const std::string& sceneFile, const std::vector<std::string>& sets,
                    std::optional<int> lights);

struct RunRecord {
  std::string id, sweep, scene, method, methodName, backend;
  Json axes = Json::object();
  int point = 0;
  std::string hash;
  std::string status;    ///< "ok", "failed", or "refused" (the method cannot render the scene)
  std::string error;     ///< the failure's message
  bool resumed = false;  ///< loaded from DIR/runs/ instead of rendered
  Json stats;            ///< RenderStats::toJson() of the last repetition, timings = medians
  std::vector<std::pair<std::string, double>> medianMs;  ///< per stage, plus "total"
  /// The stages and total of one repetition, the one whose total is closest to the median
  /// total: its stages add up to at most its total (the medians of the stages need not add up
  /// to the median total); plots.py draws its stage bars from them.
  std::vector<std::pair<std::string, double>> medianRunMs;
  int repetitions = 0, warmup = 0;
  /// The steady frames (SweepSpec::steadyFrames), null when none were drawn: frames, wall_ms
  /// (median of the method's render), gpu_ms (median of gpu_ms_total; GPU only), host_waits
  /// (the most of any frame; GPU only).
  Json steady;
  std::vector<std::string> references;  ///< names, in order
  std::vector<ImageError> errors;       ///< one per reference
  /// Reference name -> its convergence check (converged references only): steps, the relative
  /// L2 change on halving them, whether it passed or was refined.
  Json referenceChecks = Json::object();
  bool lightInMedium = false;  ///< a point or spot light lies inside the medium's box
  double peakHostMiB = 0.0;    ///< VmHWM during the run (whole process)
  double baseHostMiB = 0.0;    ///< VmRSS just before it
  std::string memoryMethod;    ///< how peakHostMiB was measured
  std::optional<long long> samples;
  std::string image;  ///< PNG path relative to DIR
  /// Reference name -> its PNG relative to DIR (references/<name>-<hash>.png), for the
  /// gallery's difference images.
  Json referenceImages = Json::object();
  /// The machine that rendered the run (machineFacts() at the start of its experiment), so that
  /// runs merged from several machines are never compared silently.
  Json machine = Json::object();
  Json paper = Json::object();
  Json config;  ///< the run's full configuration (logged with failures)

  Json toJson() const;
  static RunRecord fromJson(const Json& j);
  double totalMs() const;
  /// What the reports' "samples used" column shows: the samples, or for adaptive rendered by
  /// its whole-scene fallback (stats voxels_instead) "per-voxel: N voxels", or "—".
  std::string samplesLabel() const;
  /// steady[key] where the steady frames hold it (not on the CPU for gpu_ms, host_waits).
  std::optional<double> steadyValue(const char* key) const;
};

struct ExperimentOptions {
  std::vector<std::string> overrides;  ///< --set, applied to every render
  std::FILE* log = nullptr;            ///< one line per render (besides DIR/log.txt)
  bool progress = true;                ///< progress bar with ETA when stderr is a terminal
  bool plots = true;                   ///< call experiment/plots.py (python3 + matplotlib)
  /// `--shard K/N`: render only the K-th (1-based) of N deterministic slices of the run list
  /// (shardOf()) and write runs/, images/, references/, log.txt and shard-K-of-N.json, but no
  /// tables, report or plots: `scatterlab experiment merge` joins the shards. 0/0: everything.
  int shardIndex = 0, shardCount = 0;
  /// Merge mode (mergeShards): every run must already have its record in DIR/runs/ (failed
  /// ones included); nothing is rendered except missing references of the gallery.
  bool recordsOnly = false;
};

struct ExperimentResult {
  ExperimentPlan plan;
  std::vector<RunRecord> runs;
  /// refused: runs whose method cannot render their scene (UnsupportedSceneError), recorded
  /// with the reason; not failures.
  int rendered = 0, resumed = 0, failed = 0, refused = 0;
  std::string plotsNote;  ///< why plots are missing, or "" when they were made
  Json machine;           ///< machineFacts() of this invocation
};

/// Runs (or resumes) the experiment in `configPath`, writing into `outDir` (created if
/// missing). A failing run is recorded (status "failed", its message and config, in the
/// results and DIR/log.txt) and the sweep goes on; a run whose method cannot render its scene
/// (UnsupportedSceneError) is recorded as "refused" with the reason, kept on resume. Throws
/// ConfigError / IoError for a bad config before anything is rendered.
ExperimentResult runExperiment(const std::string& configPath, const std::string& outDir,
                               const ExperimentOptions& options = {});

/// Which shard (0-based) of `count` renders each run of `plan`, in run order. Deterministic
/// (depends only on the plan): the runs are grouped by the scene their references see (same
/// scene file, overrides and lights: one reference image per group) and each group goes whole
/// to the shard with the fewest runs so far, so that a reference is rendered by one shard only;
/// when there are fewer groups than shards, the runs are dealt round-robin instead, and shards
/// sharing a group render its reference each (same cache key, same image).
std::vector<int> shardOf(const ExperimentPlan& plan, int count);

/// Facts about this machine and build for results.json and every run record: cpu_model,
/// logical_cpus, cores_used (the process's CPU affinity), load_avg_start (1, 5, 15 min from
/// /proc/loadavg), hostname, os, commit (the git commit the binary was built from, recorded at
/// build time: "+dirty" with uncommitted changes, "unknown" when built outside a checkout). The GPU
/// renderer is per run (its stats' `device`).
Json machineFacts();

/// `scatterlab experiment merge DIR... -o OUT`: checks that the shard directories hold every
/// shard of one plan (same config and configuration hashes; ConfigError naming what is missing
/// or different, before OUT is touched), copies their runs/, images/ and references/ into OUT
/// and writes the tables, report and plots of the whole experiment there.
ExperimentResult mergeShards(const std::vector<std::string>& shardDirs, const std::string& outDir,
                             const ExperimentOptions& options = {});

/// The python interpreter the plots use: the first of $SCATTERLAB_PYTHON, `python3` on the PATH
/// and /usr/bin/python3 that can import matplotlib; "" when none can.
std::string findPlotPython();

/// One panel of a gallery strip: an image and the label lines drawn above it.
struct StripPanel {
  Image image;
  std::vector<std::string> label;
};

/// report.md's gallery strip (without plots): the panels left to right with 4-pixel gaps, each
/// under its label (white 5×7 capitals on black, wrapped to its width); with `errors`, a second
/// row of signed error maps against the first panel (the headline reference), whose own slot
/// shows the colour scale of those maps. Linear values that show so after `exposure` stops.
Image galleryStrip(const std::vector<StripPanel>& panels, bool errors, float exposure);

/// FNV-1a 64-bit hash of `text`, as 16 hex digits (stable across runs and machines).
std::string stableHash(const std::string& text);

}  // namespace scatterlab
