#include "cpu/sample_view.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>

namespace scatterlab {

Vec3 levelColour(int level) {
  static const Vec3 colours[] = {Vec3(1, 1, 1), Vec3(0.1f, 1, 0.2f), Vec3(1, 0.9f, 0.1f),
                                 Vec3(1, 0.15f, 0.1f), Vec3(1, 0.2f, 1)};
  return colours[std::clamp(level, 0, 4)];
}

DotStyle dotStyle(std::size_t count, std::size_t span) {
  // Pixels of a disc of radius 0, 1, 2 (the (x, y) offsets with x² + y² <= r²).
  static constexpr int kArea[] = {1, 5, 13};
  const double budget = kSampleCover * double(span);
  DotStyle s;
  if (count == 0) return s;
  s.radius = 0;
  for (int r = 2; r >= 1; --r)
    if (double(count) * kArea[r] <= budget) {
      s.radius = r;
      break;
    }
  s.opacity = float(std::min(1.0, budget / (double(count) * kArea[s.radius])));
  return s;
}

Image drawSamples(const Image& base, const std::vector<RadianceSample>& samples,
                  const Camera& camera, float dim, float bright) {
  Image out = base;
  for (Vec3& p : out.pixels()) p *= dim;
  int maxLevel = 0;
  for (const auto& s : samples) maxLevel = std::max(maxLevel, std::clamp(s.level, 0, 4));
  // Level by level, finer levels on top; each level's dots sized (and, where even one pixel a
  // sample covers too much, made translucent) so that they cover at most kSampleCover of the
  // area its samples project to: thousands of samples through a volume otherwise paint a solid
  // block (a scene without splits showed a white square).
  for (int level = 0; level <= maxLevel; ++level) {
    std::vector<std::pair<int, int>> px;
    std::unordered_set<long long> blocks;  // the 4×4-pixel blocks the level's samples fall in
    for (const auto& s : samples) {
      if (std::clamp(s.level, 0, 4) != level) continue;
      float fx, fy;
      if (!camera.project(s.position, fx, fy)) continue;
      const int cx = int(std::floor(fx)), cy = int(std::floor(fy));
      if (cx < 0 || cy < 0 || cx >= out.width() || cy >= out.height()) continue;
      px.emplace_back(cx, cy);
      blocks.insert((long long)(cy / 4) * ((out.width() + 3) / 4) + cx / 4);
    }
    if (px.empty()) continue;
    const DotStyle st = dotStyle(px.size(), blocks.size() * 16);
    const Vec3 colour = bright * levelColour(level);
    const int r = st.radius;
    for (const auto& [cx, cy] : px)
      for (int y = cy - r; y <= cy + r; ++y)
        for (int x = cx - r; x <= cx + r; ++x) {
          if (x < 0 || y < 0 || x >= out.width() || y >= out.height()) continue;
          if ((x - cx) * (x - cx) + (y - cy) * (y - cy) > r * r) continue;
          Vec3& p = out.at(x, y);
          p = p * (1.0f - st.opacity) + colour * st.opacity;
        }
  }
  return out;
}

}  // namespace scatterlab
