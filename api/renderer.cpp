#include "api/renderer.h"

#include <cmath>

#include "api/scatterlab.h"
#include "core/error.h"
#include "core/quick_look.h"
#include "gpu/context.h"

namespace scatterlab {

Renderer::Renderer(Json doc, std::filesystem::path baseDir, std::string method, std::string backend)
    : baseDir_(std::move(baseDir)), methodName_(std::move(method)), backend_(std::move(backend)) {
  initialize();  // idempotent: a Renderer needs no call before it
  const double t = documentTime(doc);
  rebuild(doc, t);
}

Renderer Renderer::fromFile(const std::string& path, const std::vector<std::string>& overrides,
                            std::string method, std::string backend) {
  initialize();
  Json doc = readSceneDocument(path);
  for (const auto& o : overrides) applyOverride(doc, o);
  try {
    return Renderer(std::move(doc), std::filesystem::path(path).parent_path(), std::move(method),
                    std::move(backend));
  } catch (const ConfigError& e) {
    throw ConfigError(path + ": " + e.what());
  }
}

void shareGlContextWithCurrent() {
  gpu::shareWithCurrentContext();
}

Renderer::Renderer(Renderer&&) noexcept = default;

Renderer& Renderer::operator=(Renderer&& o) noexcept {
  {
    const gpu::CallerContextGuard guard;  // the old method's GL objects die in our context
    method_.reset();
  }
  doc_ = std::move(o.doc_);
  baseDir_ = std::move(o.baseDir_);
  methodName_ = std::move(o.methodName_);
  backend_ = std::move(o.backend_);
  time_ = o.time_;
  scene_ = std::move(o.scene_);
  mediumDoc_ = std::move(o.mediumDoc_);
  objectsDoc_ = std::move(o.objectsDoc_);
  renderDoc_ = std::move(o.renderDoc_);
  method_ = std::move(o.method_);
  imageOnDevice_ = o.imageOnDevice_;
  return *this;
}

Renderer::~Renderer() {
  const gpu::CallerContextGuard guard;  // GL objects are deleted in scatterlab's context
  method_.reset();
}

void Renderer::rebuild(const Json& doc, double t, bool mediumKept) {
  const gpu::CallerContextGuard guard;  // a replaced method frees its GL objects in our context
  // Everything is parsed and created before anything is replaced: a bad value leaves the
  // renderer as it was.
  const Json work = sceneAtTime(doc, t);
  const Json none;
  const Json& medium = work.contains("medium") ? work["medium"] : none;
  const Json& render = work.contains("render") ? work["render"] : none;
  const Json& objects = work.contains("objects") ? work["objects"] : none;
  // mediumKept: `doc` has no medium (set() detached it, unchanged): the kept one stays.
  const bool sameMedium = method_ && (mediumKept || medium == mediumDoc_);
  Scene s = sameMedium ? parseScene(work, baseDir_, &scene_.medium) : parseScene(work, baseDir_);
  // The same objects stay the same object: the method sees the visibility unchanged (and
  // keeps its radiance volume where nothing else it depends on changed).
  if (method_ && objects == objectsDoc_) s.objects = scene_.objects;
  std::unique_ptr<Method> m;
  if (!sameMedium || render != renderDoc_) {
    m = createMethod(s, methodName_, backend_);
    m->retainDensity = true;
    m->imageOnDevice = imageOnDevice_;
  }
  doc_ = doc;
  time_ = t;
  scene_ = std::move(s);
  if (!mediumKept) mediumDoc_ = medium;
  objectsDoc_ = objects;
  renderDoc_ = render;
  if (m) method_ = std::move(m);
}

void Renderer::set(const std::string& assignment) {
  const std::string top = assignment.substr(0, assignment.find_first_of(".=["));
  if (method_ && top != "medium" && doc_.is_object() && doc_.contains("medium")) {
    // The medium is untouched: it is detached from the document (a move), so that neither the
    // override's copy nor rebuild's copies and comparisons walk it (fig3's 800 blobs cost ~1 ms
    // a call), and put back whatever happens.
    Json medium = std::move(doc_["medium"]);
    doc_.erase("medium");
    struct Reattach {
      Json& doc;
      Json& medium;
      ~Reattach() { doc["medium"] = std::move(medium); }
    } reattach{doc_, medium};
    Json doc = doc_;
    applyOverride(doc, assignment);
    rebuild(doc, time_, /*mediumKept=*/true);
    return;
  }
  Json doc = doc_;
  applyOverride(doc, assignment);
  rebuild(doc, time_);
}

void Renderer::setLight(std::size_t index, const Light& light) {
  if (index >= scene_.lights.size())
    throw ConfigError("setLight: lights[" + std::to_string(index) +
                      "] does not exist (the scene has " + std::to_string(scene_.lights.size()) +
                      " light(s); indices from 0)");
  set("lights." + std::to_string(index) + "=" + lightJson(light).dump());
}

void Renderer::setCamera(const Camera& camera) {
  set("camera=" + cameraJson(camera).dump());
}

void Renderer::setTime(double t) {
  if (!std::isfinite(t)) throw ConfigError("time must be finite, got " + std::to_string(t));
  if (t != time_) rebuild(doc_, t);
}

void Renderer::keepImageOnDevice(bool on) {
  imageOnDevice_ = on;
  if (method_) method_->imageOnDevice = on;
}

Method& Renderer::method() {
  return *method_;
}

RenderResult Renderer::render(Progress* progress) {
  // An engine's context current on entry is current again on return, and (shared) sees the
  // image: gpu/context.h.
  const gpu::CallerContextGuard guard;
  RenderResult r = method_->render(scene_, progress);
  r.stats.extra["time"] = time_;
  return r;
}

}  // namespace scatterlab
