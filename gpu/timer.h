#pragma once
/// Per-stage GPU times from GL_TIME_ELAPSED timer queries. Needs a current context.
/// Queries are read when results() is called (which waits for the GPU), so timing does not
/// stall the pipeline between stages.

#include <string>
#include <utility>
#include <vector>

#include "gpu/gl.h"

namespace scatterlab::gpu {

class StageTimer {
 public:
  /// Starts timing `stage`; only one stage at a time (GL allows one GL_TIME_ELAPSED query).
  void begin(const std::string& stage);
  void end();
  /// GPU milliseconds per stage, in order of begin(); stages timed more than once are summed.
  std::vector<std::pair<std::string, double>> results();

 private:
  std::vector<std::pair<std::string, Query>> queries_;
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
