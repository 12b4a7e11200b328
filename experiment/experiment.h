#pragma once
/// A minimal experiment runner (issue 4's Fig. 3 experiment; issue 7 generalises it): render
/// reference methods and a list of runs on one scene, compare every image with every
/// reference, and write images, a CSV and a Markdown table.
///
/// Config (JSON, strict: unknown keys are errors naming the key):
///   {"title": "...", "scene": "path relative to the config",
///    "set": ["key=value", ...],             // overrides applied to every render
///    "references": ["per-voxel", "exact"],  // methods; the first is the headline reference
///    "exposure": 0,                         // PNG exposure in stops
///    "runs": [{"name": "gradient", "method": "gradient", "set": ["..."],
///              "paper_rel_error": 0.043}]}  // optional, copied into the table
/// Outputs in the directory: <name>.exr and <name>.png per image, side_by_side.png
/// (references then runs, left to right, in table order), results.csv, results.md,
/// results.json.

#include <filesystem>
#include <string>
#include <vector>

#include "core/method.h"

namespace scatterlab {

struct ExperimentRow {
  std::string name, method;
  bool reference = false;
  RenderStats stats;
  std::vector<ImageError> errors;  ///< one per reference, in config order
  std::optional<double> paperRelError;
};

struct ExperimentResult {
  std::string title;
  std::vector<std::string> references;
  std::vector<ExperimentRow> rows;
};

/// Runs the experiment in `configPath` (extra `overrides` apply to every render, after the
/// config's own), writing into `outDir` (created if missing). `log` gets one line per render
/// when non-null. Throws ConfigError / IoError; outputs are written atomically one by one.
ExperimentResult runExperiment(const std::string& configPath, const std::string& outDir,
                               const std::vector<std::string>& overrides = {},
                               std::FILE* log = nullptr);

}  // namespace scatterlab
