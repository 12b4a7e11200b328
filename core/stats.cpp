#include "core/stats.h"

namespace scatterlab {

void RenderStats::addTiming(const std::string& stage, double ms) {
  for (auto& [s, t] : timingsMs)
    if (s == stage) {
      t += ms;
      return;
    }
  timingsMs.emplace_back(stage, ms);
}

double RenderStats::totalMs() const {
  double t = 0;
  for (const auto& [s, ms] : timingsMs) t += ms;
  return t;
}

Json RenderStats::toJson() const {
  Json j;
  j["method"] = method;
  j["backend"] = backend;
  j["device"] = device;
  j["width"] = width;
  j["height"] = height;
  if (samples) j["samples"] = *samples;
  Json t = Json::object();
  for (const auto& [s, ms] : timingsMs) t[s] = ms;
  t["total"] = totalMs();
  j["timings_ms"] = t;
  for (auto it = extra.begin(); it != extra.end(); ++it) j[it.key()] = it.value();
  return j;
}

}  // namespace scatterlab
