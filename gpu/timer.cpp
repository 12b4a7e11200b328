#include "gpu/timer.h"

#include "core/error.h"

namespace scatterlab::gpu {

void StageTimer::begin(const std::string& stage) {
  if (open_) throw GpuError("StageTimer: '" + stage + "' begun inside another stage");
  queries_.emplace_back(stage, Query(GL_TIME_ELAPSED, "timer " + stage));
  glBeginQuery(GL_TIME_ELAPSED, queries_.back().second.id());
  open_ = true;
}

void StageTimer::end() {
  if (!open_) return;
  glEndQuery(GL_TIME_ELAPSED);
  open_ = false;
}

std::vector<std::pair<std::string, double>> StageTimer::results() {
  end();
  std::vector<std::pair<std::string, double>> out;
  for (auto& [name, q] : queries_) {
    GLuint64 ns = 0;
    glGetQueryObjectui64v(q.id(), GL_QUERY_RESULT, &ns);
    const double ms = double(ns) * 1e-6;
    bool merged = false;
    for (auto& [n, v] : out)
      if (n == name) {
        v += ms;
        merged = true;
      }
    if (!merged) out.emplace_back(name, ms);
  }
  queries_.clear();
  return out;
}

}  // namespace scatterlab::gpu
