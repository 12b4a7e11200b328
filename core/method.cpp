#include "core/method.h"

#include <algorithm>

#include "core/suggest.h"

namespace scatterlab {

Registry<MethodEntry>& methods() {
  static Registry<MethodEntry> r("method");
  return r;
}

namespace {

/// The backend a method runs on: "cpu" and "gpu" as asked (an error where the method or this
/// build has no such variant), "auto" the GPU when its backend prefers itself now (a hardware
/// GPU) and the method runs there, else the CPU. `note` says why, for "auto".
Backend chooseBackend(const Scene& scene, const std::string& name, const MethodEntry& m,
                      const std::string& asked, std::string* note) {
  const BackendEntry& gpu = backends()[int(Backend::Gpu)];
  // What the GPU backend cannot render yet (its own limitation, gpu/register.cpp): refused when
  // asked for, avoided by "auto".
  const std::string gpuLacks = gpu.unsupported ? gpu.unsupported(scene) : "";
  if (asked == "gpu" && !gpuLacks.empty()) throw ConfigError(gpuLacks);
  if (asked == "auto" && !gpuLacks.empty() && m.runsOn(Backend::Cpu) && m.runsOn(Backend::Gpu)) {
    *note = "auto: " + gpuLacks.substr(0, gpuLacks.find(';')) + "; using the CPU";
    return Backend::Cpu;
  }
  if (asked == "cpu") {
    if (!m.runsOn(Backend::Cpu))
      throw ConfigError("method '" + name + "' has no CPU variant; use --backend gpu");
    return Backend::Cpu;
  }
  if (asked == "gpu") {
    if (!gpu.makeFrame) throw ConfigError("this build of scatterlab has no GPU backend");
    if (!m.runsOn(Backend::Gpu))
      throw ConfigError("method '" + name + "' has no GPU variant; use --backend cpu");
    return Backend::Gpu;
  }
  if (!m.runsOn(Backend::Gpu)) {
    *note = "auto: method '" + name + "' runs on the CPU only";
    return Backend::Cpu;
  }
  if (!gpu.preferred) {
    *note = "auto: no GPU backend in this build; using the CPU";
    return Backend::Cpu;
  }
  return gpu.preferred(note) ? Backend::Gpu : Backend::Cpu;
}

}  // namespace

std::unique_ptr<Method> createMethod(const Scene& scene, const std::string& methodOverride,
                                     const std::string& backend) {
  const std::vector<std::string> backendNames{"cpu", "gpu", "auto"};
  // Checked first: a misspelt backend ('GPU', 'cuda', '') must not quietly run on auto.
  if (std::find(backendNames.begin(), backendNames.end(), backend) == backendNames.end())
    throw ConfigError("backend: unknown backend '" + backend + "'" +
                      didYouMean(backend, backendNames) + "; allowed: 'cpu', 'gpu', 'auto'");
  Params p(scene.render, "render");
  std::string name = p.string("method", std::string(kDefaultMethod));
  if (!methodOverride.empty()) name = methodOverride;
  const std::string fromFile = p.choice("backend", backendNames, "auto");
  const std::string asked = backend == "auto" ? fromFile : backend;
  const MethodEntry& entry =
      methods().get(name, methodOverride.empty() ? "render.method" : "method");
  std::string note;
  const Backend b = chooseBackend(scene, name, entry, asked, &note);
  auto method = entry.create(p, scene, b, note);
  // Keys of other registered methods are tolerated (and reported); the rest is an error.
  std::vector<std::string> ignored;
  for (auto it = scene.render.begin(); it != scene.render.end(); ++it) {
    if (std::find(entry.keys.begin(), entry.keys.end(), it.key()) != entry.keys.end()) continue;
    for (const std::string& other : methods().names()) {
      const auto& keys = methods().get(other, "render.method").keys;
      if (std::find(keys.begin(), keys.end(), it.key()) != keys.end()) {
        ignored.push_back(p.keyPath(it.key()));
        p.allow(it.key());
        break;
      }
    }
  }
  p.finish();
  method->ignoredKeys = std::move(ignored);
  return method;
}

}  // namespace scatterlab
