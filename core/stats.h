#pragma once
/// What a render did: method, backend, device, sizes, sample counts, per-stage times.

#include <chrono>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/params.h"

namespace scatterlab {

struct RenderStats {
  std::string method, backend = "cpu", device;
  int width = 0, height = 0;
  std::optional<long long> samples;                       ///< radiance samples, when a sampler ran
  std::vector<std::pair<std::string, double>> timingsMs;  ///< per stage, in order
  Json extra = Json::object();  ///< method-specific facts (traced voxels, levels, ...)

  void addTiming(const std::string& stage, double ms);
  double totalMs() const;
  /// JSON with method, backend, device, width, height, samples, timings_ms{stage..., total}.
  Json toJson() const;
};

/// Adds the elapsed wall time of its scope to stats under `stage`.
class ScopedTimer {
 public:
  ScopedTimer(RenderStats& stats, std::string stage)
      : stats_(stats), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}
  ~ScopedTimer() {
    const auto d = std::chrono::steady_clock::now() - start_;
    stats_.addTiming(stage_, std::chrono::duration<double, std::milli>(d).count());
  }

 private:
  RenderStats& stats_;
  std::string stage_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace scatterlab
