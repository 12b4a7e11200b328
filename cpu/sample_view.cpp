#include "cpu/sample_view.h"

#include <algorithm>

namespace scatterlab {

Vec3 levelColour(int level) {
  static const Vec3 colours[] = {Vec3(1, 1, 1), Vec3(0.1f, 1, 0.2f), Vec3(1, 0.9f, 0.1f),
                                 Vec3(1, 0.15f, 0.1f), Vec3(1, 0.2f, 1)};
  return colours[std::clamp(level, 0, 4)];
}

Image drawSamples(const Image& base, const std::vector<RadianceSample>& samples,
                  const Camera& camera, float dim, float bright) {
  Image out = base;
  for (Vec3& p : out.pixels()) p *= dim;
  std::vector<const RadianceSample*> order;
  for (const auto& s : samples) order.push_back(&s);
  std::stable_sort(
      order.begin(), order.end(),
      [](const RadianceSample* a, const RadianceSample* b) { return a->level < b->level; });
  for (const RadianceSample* s : order) {
    float px, py;
    if (!camera.project(s->position, px, py)) continue;
    const int r = s->level == 0 ? 2 : 1;
    const int cx = int(std::floor(px)), cy = int(std::floor(py));
    for (int y = cy - r; y <= cy + r; ++y)
      for (int x = cx - r; x <= cx + r; ++x) {
        if (x < 0 || y < 0 || x >= out.width() || y >= out.height()) continue;
        if ((x - cx) * (x - cx) + (y - cy) * (y - cy) > r * r) continue;
        out.at(x, y) = bright * levelColour(s->level);
      }
  }
  return out;
}

}  // namespace scatterlab
