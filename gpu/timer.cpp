#include "gpu/timer.h"

#include "core/error.h"

namespace scatterlab::gpu {

void StageTimer::begin(const std::string& stage) {
  if (open_) throw GpuError("StageTimer: '" + stage + "' begun inside another stage");
  spans_.push_back(
      {stage, Query(GL_TIMESTAMP, "start " + stage), Query(GL_TIMESTAMP, "end " + stage)});
  glQueryCounter(spans_.back().start.id(), GL_TIMESTAMP);
  open_ = true;
}

void StageTimer::end() {
  if (!open_) return;
  glQueryCounter(spans_.back().stop.id(), GL_TIMESTAMP);
  open_ = false;
}

std::vector<std::pair<std::string, double>> StageTimer::spans() {
  end();
  std::vector<std::pair<std::string, double>> out;
  out.reserve(spans_.size());
  if (!spans_.empty()) countHostWait("timer query results");
  for (Span& s : spans_) {
    GLuint64 t0 = 0, t1 = 0;
    glGetQueryObjectui64v(s.start.id(), GL_QUERY_RESULT, &t0);
    glGetQueryObjectui64v(s.stop.id(), GL_QUERY_RESULT, &t1);
    out.emplace_back(s.stage, t1 > t0 ? double(t1 - t0) * 1e-6 : 0.0);
  }
  spans_.clear();
  return out;
}

std::vector<std::pair<std::string, double>> StageTimer::results() {
  std::vector<std::pair<std::string, double>> out;
  for (const auto& [stage, ms] : spans()) {
    bool merged = false;
    for (auto& [n, v] : out)
      if (n == stage) {
        v += ms;
        merged = true;
      }
    if (!merged) out.emplace_back(stage, ms);
  }
  return out;
}

}  // namespace scatterlab::gpu
