#include "core/progress.h"

#include <unistd.h>

#include <cstdio>

namespace scatterlab {

Progress::Progress(std::string label, long long total, bool enabled)
    : label_(std::move(label)), total_(total), enabled_(enabled && ::isatty(STDERR_FILENO)) {
  start_ = lastDraw_ = std::chrono::steady_clock::now();
}

Progress::~Progress() {
  if (enabled_ && drawn_) draw(true);
}

void Progress::restart(std::string label, long long total) {
  if (enabled_ && drawn_) draw(true);
  std::lock_guard<std::mutex> lock(mutex_);
  label_ = std::move(label);
  total_ = total;
  done_ = 0;
  drawn_ = false;
  start_ = lastDraw_ = std::chrono::steady_clock::now();
}

void Progress::advance(long long n) {
  if (!enabled_) return;
  done_ += n;
  const auto now = std::chrono::steady_clock::now();
  // Draw only after half a second, so quick renders stay quiet, then at most 10 times a second.
  if (now - start_ < std::chrono::milliseconds(500) ||
      now - lastDraw_ < std::chrono::milliseconds(100))
    return;
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;
  lastDraw_ = now;
  draw(false);
}

void Progress::draw(bool final) {
  const long long done = final ? total_ : done_.load();
  const double f = total_ > 0 ? double(done) / double(total_) : 1.0;
  const int width = 30, filled = int(f * width + 0.5);
  const double el =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double eta = f > 0 ? el * (1.0 - f) / f : 0.0;
  std::fprintf(stderr, "\r%-12s [%.*s%*s] %3d%%  %.1fs elapsed, ETA %.1fs%s", label_.c_str(),
               filled, "##############################", width - filled, "", int(f * 100 + 0.5), el,
               eta, final ? "\n" : "");
  std::fflush(stderr);
  drawn_ = true;
}

}  // namespace scatterlab
