// libFuzzer target: the whole scene loader and the experiment-config parser, without rendering.
// Built and run by scripts/fuzz.sh. The first byte chooses:
//
//  - even: the rest is a scene file → loadScene (what `scatterlab render` calls: strict JSON,
//    medium, lights, camera, objects, validation), then createMethod on the CPU (every key of
//    the method's settings, the sampler, dynamic sampling, the memory and work bounds checked
//    before rendering). (byte / 2) mod (methods + 1) picks the method: 0 is the scene's own
//    render.method, k the k-th registered method.
//  - odd: the rest is an experiment config → parseExperiment (config keys, scenes, sweeps, the
//    run-count bound, run ids), then for at most 4 runs buildRunScene + createMethod, as
//    `scatterlab experiment` does before it renders a run.
//
// Nothing is rendered. Media that reference files (keys "file", "frames") are refused by the
// target before loading (the .vdb and .sog readers have their own targets, and a file read per
// input would be slow); so are absolute paths and ".." other than the leading "../scenes/" by
// which configs name scenes, so that no input can name /dev/zero. The config is written to
// DIR/experiments/ beside DIR/scenes/, a copy of the analytic scenes of data/scenes/.
// Any exception other than scatterlab::Error is a finding, as is any sanitizer report.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/method.h"
#include "core/params.h"
#include "core/scene.h"
#include "cpu/integrators.h"
#include "cpu/interpolation.h"
#include "cpu/radiance_evaluator.h"
#include "experiment/experiment.h"
#include "media/register.h"
#include "methods/register.h"
#include "sampling/dynamic_sampling.h"
#include "sampling/samplers.h"

#ifndef FUZZ_SOURCE_DIR
#error "FUZZ_SOURCE_DIR (the repository root) must be defined: scripts/fuzz.sh does"
#endif

using namespace scatterlab;
namespace fs = std::filesystem;

namespace {

/// Whether the document names something the target does not load (see the file comment).
bool refused(const Json& j) {
  const auto badString = [](const std::string& s) {
    if (s.find("file") != std::string::npos || s.find("frames") != std::string::npos) return true;
    if (!s.empty() && s[0] == '/') return true;
    const std::string scenes = "../scenes/";
    const std::size_t from = s.compare(0, scenes.size(), scenes) == 0 ? scenes.size() : 0;
    return s.find("..", from) != std::string::npos;
  };
  if (j.is_string()) return badString(j.get_ref<const std::string&>());
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it)
      if (badString(it.key()) || refused(it.value())) return true;
  } else if (j.is_array()) {
    for (const Json& e : j)
      if (refused(e)) return true;
  }
  return false;
}

struct Workspace {
  fs::path dir, scene, config;
  std::vector<std::string> methodNames;

  Workspace() {
    dir = fs::temp_directory_path() / ("fuzz_scene_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir / "experiments");
    fs::create_directories(dir / "scenes");
    for (const auto& e : fs::directory_iterator(fs::path(FUZZ_SOURCE_DIR) / "data" / "scenes")) {
      if (e.path().extension() != ".json") continue;
      std::ifstream in(e.path());
      const std::string text((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
      if (text.find("\"file\"") != std::string::npos ||
          text.find("\"frames\"") != std::string::npos)
        continue;
      fs::copy_file(e.path(), dir / "scenes" / e.path().filename());
    }
    scene = dir / "scenes" / "input.json";
    config = dir / "experiments" / "input.json";
    registerMediaModels();
    registerSamplers();
    registerRadianceEvaluators();
    registerRefiners();
    registerReconstructions();
    registerIntegrators();
    registerMethods();
    methodNames = methods().names();
  }
};

Workspace& workspace() {
  static Workspace w;
  return w;
}

void write(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), std::streamsize(bytes.size()));
}

void fuzzScene(Workspace& w, std::uint8_t selector, const std::string& text) {
  write(w.scene, text);
  const std::size_t pick = (selector / 2) % (w.methodNames.size() + 1);
  try {
    const Scene scene = loadScene(w.scene.string());
    (void)createMethod(scene, pick == 0 ? "" : w.methodNames[pick - 1], "cpu");
  } catch (const Error&) {
  }
}

void fuzzExperiment(Workspace& w, const std::string& text) {
  write(w.config, text);
  // parseExperiment reads from the working directory's point of view: scene paths in the
  // config are relative to the config's directory.
  try {
    const ExperimentPlan plan = parseExperiment(w.config.string());
    for (std::size_t i = 0; i < plan.runs.size() && i < 4; ++i) {
      const RunSpec& r = plan.runs[i];
      try {
        const Scene scene = buildRunScene(r.sceneSpec->file, r.sets, r.lights);
        (void)createMethod(scene, r.spec->method, "cpu");
      } catch (const Error&) {
      }
    }
  } catch (const Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  Workspace& w = workspace();
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  // Refuse inputs that name files (see above); what does not parse goes on to the loaders,
  // whose own errors are under test.
  try {
    if (refused(parseJson(text, "'fuzz'"))) return 0;
  } catch (const Error&) {
  }
  if (data[0] % 2 == 0)
    fuzzScene(w, data[0], text);
  else
    fuzzExperiment(w, text);
  return 0;
}
