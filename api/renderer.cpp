#include "api/renderer.h"

#include <cmath>
#include <optional>

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
  // renderer as it was. `doc` may be doc_ itself (set() changes it in place).
  Json atTime;
  const bool moves = documentMovesWithTime(doc);
  if (moves) atTime = sceneAtTime(doc, t);
  const Json& work = moves ? atTime : doc;  // a still document is its own scene: no copy
  const Json none;
  const Json& medium = work.contains("medium") ? work["medium"] : none;
  const Json& render = work.contains("render") ? work["render"] : none;
  const Json& objects = work.contains("objects") ? work["objects"] : none;
  // mediumKept: `doc` has no medium (set() detached it, unchanged): the kept one stays.
  const bool sameMedium = method_ && (mediumKept || medium == mediumDoc_);
  Scene s = sameMedium ? parseScene(work, baseDir_, &scene_.medium) : parseScene(work, baseDir_);
  // The same objects stay the same object: the method sees the visibility unchanged (and
  // keeps its radiance volume where nothing else it depends on changed).
  const bool sameObjects = method_ && objects == objectsDoc_;
  if (sameObjects) s.objects = scene_.objects;
  const bool sameRender = render == renderDoc_;
  std::unique_ptr<Method> m;
  if (!sameMedium || !sameRender) {
    m = createMethod(s, methodName_, backend_);
    m->retainDensity = true;
    m->imageOnDevice = imageOnDevice_;
  }
  if (&doc != &doc_) doc_ = doc;
  time_ = t;
  scene_ = std::move(s);
  if (!mediumKept) mediumDoc_ = medium;
  if (!sameObjects) objectsDoc_ = objects;
  if (!sameRender) renderDoc_ = render;
  if (m) method_ = std::move(m);
}

namespace {

/// What an assignment to `path` of `doc` can change, saved so that it can be put back: the
/// element `top.N` where `top` is an array with an element N (an override never grows or
/// shrinks an array, so nothing outside the element moves), else the whole top-level key (or
/// its absence).
class SavedPart {
 public:
  SavedPart(Json& doc, const std::string& path) : doc_(doc) {
    const std::size_t dot = path.find('.');
    top_ = path.substr(0, dot);
    if (!doc.contains(top_)) return;
    had_ = true;
    Json& t = doc[top_];
    if (dot != std::string::npos && t.is_array()) {
      const std::string part = path.substr(dot + 1, path.find('.', dot + 1) - dot - 1);
      if (isOverrideIndex(part) && std::stoul(part) < t.size()) {
        index_ = std::stoul(part);
        old_ = t[*index_];
        return;
      }
    }
    old_ = t;
  }
  void restore() {
    if (!had_)
      doc_.erase(top_);
    else if (index_)
      doc_[top_][*index_] = std::move(old_);
    else
      doc_[top_] = std::move(old_);
  }

 private:
  Json& doc_;
  std::string top_;
  bool had_ = false;
  std::optional<std::size_t> index_;
  Json old_;
};

}  // namespace

void Renderer::set(const std::string& assignment) {
  setAll({assignment});
}

void Renderer::setAll(const std::vector<std::string>& assignments) {
  if (assignments.empty()) return;
  bool touchesMedium = false;
  for (const std::string& a : assignments)
    touchesMedium = touchesMedium || a.substr(0, a.find_first_of(".=[")) == "medium";
  if (!method_ || touchesMedium || !doc_.is_object() || !doc_.contains("medium")) {
    Json doc = doc_;
    for (const std::string& a : assignments) applyOverride(doc, a);
    rebuild(doc, time_);
    return;
  }
  // The medium is untouched: it is detached from the document (a move), so that no copy or
  // comparison walks it (fig3's 800 blobs cost ~1 ms a call), and put back whatever happens.
  // The rest is changed in place, with what each assignment can change saved (a light of 64,
  // not the document) and put back, last first, when one fails (bench BM_RendererSet,
  // docs/benchmarks.md).
  Json medium = std::move(doc_["medium"]);
  doc_.erase("medium");
  struct Reattach {
    Json& doc;
    Json& medium;
    ~Reattach() { doc["medium"] = std::move(medium); }
  } reattach{doc_, medium};
  for (const std::string& a : assignments) checkOverrideSyntax(a);
  std::vector<SavedPart> saved;
  saved.reserve(assignments.size());
  try {
    for (const std::string& a : assignments) {
      saved.emplace_back(doc_, a.substr(0, a.find('=')));
      applyOverride(doc_, a);
    }
    rebuild(doc_, time_, /*mediumKept=*/true);
  } catch (...) {
    for (auto it = saved.rbegin(); it != saved.rend(); ++it) it->restore();
    throw;
  }
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
