#pragma once
/// Per-stage GPU times from timer queries: a GL_TIMESTAMP (glQueryCounter) at the start and the
/// end of each stage. (GL_TIME_ELAPSED begin/end pairs returned garbage on Mesa 22.3 llvmpipe
/// when no rendering preceded the begin.) Needs a current context.
/// Queries are read when results() is called (which waits for the GPU), so timing does not
/// stall the pipeline between stages.

#include <string>
#include <utility>
#include <vector>

#include "gpu/gl.h"

namespace scatterlab::gpu {

class StageTimer {
 public:
  /// Starts timing `stage`; stages do not nest.
  void begin(const std::string& stage);
  void end();
  /// GPU milliseconds per stage, in order of begin(); stages timed more than once are summed.
  std::vector<std::pair<std::string, double>> results();
  /// GPU milliseconds of every span, in order of begin() (not summed). Like results(), waits
  /// for the GPU and forgets the spans.
  std::vector<std::pair<std::string, double>> spans();
  /// Spans begun so far (since the last results() or spans()).
  std::size_t count() const { return spans_.size(); }

 private:
  struct Span {
    std::string stage;
    Query start, stop;
  };
  std::vector<Span> spans_;
  bool open_ = false;
};

/// Scope guard: times its scope as `stage` when `timer` is not null.
class ScopedGpuTimer {
 public:
  ScopedGpuTimer(StageTimer* timer, const std::string& stage) : timer_(timer) {
    if (timer_) timer_->begin(stage);
  }
  ~ScopedGpuTimer() {
    if (timer_) timer_->end();
  }
  ScopedGpuTimer(const ScopedGpuTimer&) = delete;
  ScopedGpuTimer& operator=(const ScopedGpuTimer&) = delete;

 private:
  StageTimer* timer_;
};

}  // namespace scatterlab::gpu
