/// `scatterlab fit IN.vdb [IN2.vdb ...] -o OUT.sog`: sum-of-Gaussians + residual-hash models.

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "api/scatterlab.h"
#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/limits.h"
#include "media/dense_grid.h"
#include "media/sog_fit.h"
#include "media/vdb.h"

namespace scatterlab::cli {

namespace {

struct FitArgs {
  std::vector<std::string> inputs;
  std::string output;
  std::string grid = "density";
  int gaussians = 512;
  double threshold = SogFitOptions{}.threshold;
  int bits = 8;
  std::string residual = "diffuse";
  long long fitVoxels = SogFitOptions{}.fitVoxels;
  long long maxVoxels = 160LL * 160 * 160;  // above every shared input (smoke1: 2.76 M)
  int sweeps = SogFitOptions{}.sweeps;
  bool verbose = false;
  bool imageCheck = true;
  std::string imageScene;  ///< scene file for the image check; empty: sogCheckScene
};

std::string frameName(const std::string& pattern, size_t frame) {
  char num[24];  // room for any size_t
  std::snprintf(num, sizeof num, "%04zu", frame);
  std::string s = pattern;
  s.replace(s.find("{frame}"), 7, num);
  return s;
}

struct ImageCheck {
  double relL2 = 0;
  std::string view;
  double seconds = 0;
};

/// The fit's effect in image space: the same scene rendered with `exact` on the CPU, once
/// with the input grid and once with the model; relative L2 of the second against the first.
ImageCheck imageCheck(const DensityGrid& D, const SogModel& m, const std::string& sceneFile) {
  const auto t0 = std::chrono::steady_clock::now();
  ImageCheck out;
  Scene scene;
  if (sceneFile.empty()) {
    scene = sogCheckScene(D);
    char buf[160];
    std::snprintf(buf, sizeof buf, "%dx%d, exact, sigma_t %.3g, one directional light",
                  scene.camera.width, scene.camera.height, double(scene.medium.sigmaT));
    out.view = buf;
  } else {
    scene = loadScene(sceneFile);
    scene.medium.density = std::make_shared<DenseGridDensity>(D, "the fitted input");
    out.view = sceneFile + ", exact";
  }
  const Image ref = createMethod(scene, "exact", "cpu")->render(scene, nullptr).image;
  scene.medium.density = std::make_shared<SogDensity>(m, "the fitted model");
  const Image img = createMethod(scene, "exact", "cpu")->render(scene, nullptr).image;
  out.relL2 = compareImages(img, ref).relL2;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

/// Bytes per input cell a fit takes at its peak: the dense input, the clamped model grid and
/// the residual's dense decode (4 each), the residual hash at load factor 1/2 (12) and the
/// working grids (4). Measured: a 512^3 input peaked at 3.8 GB (28.3 bytes per cell).
constexpr double kFitBytesPerCell = 28.0;

/// The VDB grid resampled to at most `maxVoxels` cells, after checking the fit's memory.
DensityGrid loadFitInput(const std::string& path, const std::string& grid, long long maxVoxels) {
  const auto vdb = VdbDensity::load(path, grid);
  const IVec3 n = vdb->nativeDims(maxVoxels);
  const double cells = double(n.x) * n.y * n.z;
  checkMemory(path,
              "fitting its " + std::to_string(n.x) + "x" + std::to_string(n.y) + "x" +
                  std::to_string(n.z) + " grid (lower it with --max-voxels)",
              cells * kFitBytesPerCell);
  DensityGrid D(*vdb->naturalBounds(), n);
  vdb->build(D);
  return D;
}

int runFit(const FitArgs& a) {
  const bool sequence = a.inputs.size() > 1;
  if (sequence && a.output.find("{frame}") == std::string::npos)
    throw ConfigError("fit: with " + std::to_string(a.inputs.size()) +
                      " input frames, -o must contain '{frame}' (replaced by 0000, 0001, ...); "
                      "got '" +
                      a.output + "'");
  // Check every input and output before the (slow) fitting, so a bad argument costs nothing.
  std::vector<std::string> outputs;
  for (size_t f = 0; f < a.inputs.size(); ++f) {
    checkReadableFile(a.inputs[f], "VDB file");
    outputs.push_back(sequence ? frameName(a.output, f) : a.output);
    checkWritablePath(outputs.back());
  }
  // An output must not overwrite an input (the same input twice is a legitimate sequence).
  for (size_t f = 0; f < a.inputs.size(); ++f)
    for (size_t g = 0; g < outputs.size(); ++g)
      checkDistinctPaths({{"input " + a.inputs[f], a.inputs[f]},
                          {"--output (frame " + std::to_string(g) + ")", outputs[g]}});
  if (!a.imageScene.empty()) {
    if (!a.imageCheck)
      throw ConfigError("fit: --image-scene and --no-image-check contradict each other");
    loadScene(a.imageScene);  // a bad scene fails now, not after the fit
  }
  SogFitOptions o;
  o.gaussians = a.gaussians;
  o.threshold = a.threshold;
  o.bits = a.bits;
  o.residual = a.residual == "drop" ? SogResidualMode::Drop : SogResidualMode::Diffuse;
  o.fitVoxels = a.fitVoxels;
  o.sweeps = a.sweeps;
  if (a.verbose) o.log = [](const std::string& s) { std::printf("  %s\n", s.c_str()); };
  PendingOutputs pending;  // all frames appear together, or none
  std::vector<GaussianBlob> previous;
  for (size_t f = 0; f < a.inputs.size(); ++f) {
    const DensityGrid D = loadFitInput(a.inputs[f], a.grid, a.maxVoxels);
    const IVec3 n = D.dims();
    // Frames after the first start from the previous frame's Gaussians (temporal coherence).
    o.init = previous.empty() ? nullptr : &previous;
    SogFitReport rep;
    const SogModel m = fitSog(D, o, &rep);
    previous = m.gaussians;
    pending.stage(outputs[f], [&](const std::string& tmp) { writeSog(tmp, m); });
    const double denseBytes = double(D.size()) * sizeof(float);
    std::printf("%s -> %s\n", a.inputs[f].c_str(), outputs[f].c_str());
    std::printf("  input grid       %dx%dx%d (%.0f cells, %.1f MB as dense float32)\n", n.x, n.y,
                n.z, double(D.size()), denseBytes / 1e6);
    std::printf("  gaussians        %d (working grid %dx%dx%d)\n", rep.gaussians, rep.fitDims.x,
                rep.fitDims.y, rep.fitDims.z);
    std::printf("  hash entries     %zu (%d-bit, |F| > %g)\n", rep.hashEntries, a.bits,
                double(m.threshold));
    std::printf("  bytes on disk    %zu (%.2f%% of the dense grid's %.0f)\n", m.fileBytes(),
                100.0 * double(m.fileBytes()) / denseBytes, denseBytes);
    std::printf("  rel. L2 D~       %.5f\n", rep.relL2Gaussians);
    std::printf("  rel. L2 D~ + F   %.5f\n", rep.relL2Model);
    std::printf("  mass change      %+.3f%% (sum over the input cells)\n",
                100.0 * rep.relMassModel);
    if (a.imageCheck) {
      const ImageCheck ic = imageCheck(D, m, a.imageScene);
      std::printf("  image rel. L2    %.5f (model vs input rendered: %s; %.2f s)\n", ic.relL2,
                  ic.view.c_str(), ic.seconds);
    }
    std::printf(
        "  time             %.2f s (placement %.2f, refinement %.2f, weights %.2f, "
        "residual %.2f)\n",
        rep.secondsTotal, rep.secondsPlacement, rep.secondsRefinement, rep.secondsWeights,
        rep.secondsResidual);
  }
  pending.commit();
  return 0;
}

}  // namespace

Action addFit(CLI::App& app) {
  auto a = std::make_shared<FitArgs>();
  CLI::App* c = app.add_subcommand(
      "fit", "Fit a sum-of-Gaussians + residual-hash model (.sog) to OpenVDB density frames");
  c->add_option("inputs", a->inputs, "Input .vdb file(s); several = a sequence of frames")
      ->required();
  c->add_option("-o,--output", a->output,
                "Output .sog file; for a sequence a pattern with {frame} (0000, 0001, ...)")
      ->required();
  c->add_option("--grid", a->grid, "Name of the float grid to read")->capture_default_str();
  c->add_option("-n,--gaussians", a->gaussians, "Number of Gaussians")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  c->add_option("--threshold", a->threshold, "Residual kept where |F| > threshold * max density")
      ->check(CLI::Range(0.0, 0.999))
      ->capture_default_str();
  c->add_option("--bits", a->bits, "Residual quantisation bits (8 or 16)")
      ->check(CLI::IsMember({8, 16}))
      ->capture_default_str();
  c->add_option("--residual", a->residual,
                "Residual below the threshold: diffuse (carried to neighbouring cells, mass "
                "kept) or drop (lost; the original fit)")
      ->check(CLI::IsMember({"diffuse", "drop"}))
      ->capture_default_str();
  c->add_option("--fit-voxels", a->fitVoxels,
                "Cell budget of the working grid for placement and refinement")
      ->check(CLI::Range(8LL, 512LL * 512 * 512))
      ->capture_default_str();
  c->add_option("--max-voxels", a->maxVoxels,
                "Cells of the input grid at most: a larger VDB is resampled to fit (bounds the "
                "fit's memory, about 28 bytes per cell, and time)")
      ->check(CLI::Range(8LL, 512LL * 512 * 512))
      ->capture_default_str();
  c->add_option("--sweeps", a->sweeps, "Levenberg-Marquardt refinement sweeps")
      ->check(CLI::Range(0, 100))
      ->capture_default_str();
  c->add_flag("!--no-image-check", a->imageCheck,
              "Skip rendering the input and the model to report the fit's image-space error");
  c->add_option("--image-scene", a->imageScene,
                "Scene for the image check (its density replaced by the input, then the model); "
                "default: a 160x120 view of the model's box with one light");
  c->add_flag("-v,--verbose", a->verbose, "Print the fitting steps");
  return [a]() { return runFit(*a); };
}

}  // namespace scatterlab::cli
