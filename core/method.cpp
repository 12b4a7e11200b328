#include "core/method.h"

namespace scatterlab {

Registry<MethodFactory>& methods() {
  static Registry<MethodFactory> r("method");
  return r;
}

namespace {

std::string backendOf(Params& p, const std::string& requested) {
  const std::string fromFile = p.choice("backend", {"cpu", "gpu", "auto"}, "auto");
  return requested.empty() || requested == "auto" ? fromFile : requested;
}

}  // namespace

std::unique_ptr<Method> createMethod(const Scene& scene, const std::string& methodOverride,
                                     const std::string& backend) {
  Params p(scene.render, "render");
  const std::string fileMethod = p.string("method", "exact");
  const std::string b = backendOf(p, backend);
  const std::string name = methodOverride.empty() ? fileMethod : methodOverride;
  auto method =
      methods().get(name, methodOverride.empty() ? "render.method" : "--method")(p, scene, b);
  if (name != fileMethod && methods().contains(fileMethod)) {
    // Validate the file's own settings with its own method, then accept its keys here.
    // Validated for key checking only, on its own backend setting: the requested backend
    // applies to the overriding method, which may support it where the file's does not.
    Params own(scene.render, "render");
    own.string("method", "exact");
    methods().get(fileMethod, "render.method")(own, scene, backendOf(own, "auto"));
    own.finish();
    for (auto it = scene.render.begin(); it != scene.render.end(); ++it) p.allow(it.key());
  }
  p.finish();
  return method;
}

}  // namespace scatterlab
