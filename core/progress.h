#pragma once
/// Progress bar on stderr when it is a terminal; silent otherwise. Thread-safe advance().

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>

namespace scatterlab {

class Progress {
 public:
  /// enabled = false (or stderr not a terminal) makes every call a no-op.
  Progress(std::string label, long long total, bool enabled = true);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void advance(long long n = 1);
  /// Starts a new phase with a new label and total.
  void restart(std::string label, long long total);

 private:
  void draw(bool final);

  std::string label_;
  std::atomic<long long> done_{0};
  long long total_;
  bool enabled_;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_, lastDraw_;
  bool drawn_ = false;
};

}  // namespace scatterlab
