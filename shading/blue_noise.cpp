#include "shading/blue_noise.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace scatterlab {

namespace {

/// Void-and-cluster (Ulichney 1993) on a torus of n × n: ranks 0 … n²−1 so that every prefix
/// of the ranking is a blue-noise point set.
std::vector<float> voidAndCluster(int n) {
  const int N = n * n;
  const float sigma = 1.5f;
  // Toroidal Gaussian kernel by offset.
  std::vector<float> kernel(N);
  for (int dy = 0; dy < n; ++dy)
    for (int dx = 0; dx < n; ++dx) {
      const int ex = std::min(dx, n - dx), ey = std::min(dy, n - dy);
      kernel[dy * n + dx] = std::exp(-float(ex * ex + ey * ey) / (2.0f * sigma * sigma));
    }
  std::vector<uint8_t> bits(N, 0);
  std::vector<float> energy(N, 0.0f);
  const auto update = [&](int p, float sign) {
    const int px = p % n, py = p / n;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        energy[y * n + x] += sign * kernel[((y - py + n) % n) * n + ((x - px + n) % n)];
  };
  // The tightest cluster (highest energy among set points) or the largest void (lowest energy
  // among unset points); ties to the lowest index, so the result is deterministic.
  const auto extreme = [&](uint8_t value, bool highest) {
    int best = -1;
    for (int p = 0; p < N; ++p)
      if (bits[p] == value &&
          (best < 0 || (highest ? energy[p] > energy[best] : energy[p] < energy[best])))
        best = p;
    return best;
  };
  // Initial pattern: N/10 points from a fixed linear congruential sequence.
  uint32_t state = 12345u;
  const int ones = N / 10;
  for (int placed = 0; placed < ones;) {
    state = state * 1664525u + 1013904223u;
    const int p = int((state >> 8) % uint32_t(N));
    if (bits[p]) continue;
    bits[p] = 1;
    update(p, 1.0f);
    ++placed;
  }
  // Spread it: move the tightest cluster's point into the largest void until they coincide.
  for (int it = 0; it < 4 * N; ++it) {
    const int c = extreme(1, true);
    bits[c] = 0;
    update(c, -1.0f);
    const int v = extreme(0, false);
    bits[v] = 1;
    update(v, 1.0f);
    if (v == c) break;
  }
  const std::vector<uint8_t> initial = bits;
  const std::vector<float> initialEnergy = energy;
  std::vector<int> rank(N, -1);
  // Phase 1: ranks ones−1 … 0 by removing tightest clusters.
  for (int r = ones - 1; r >= 0; --r) {
    const int c = extreme(1, true);
    bits[c] = 0;
    update(c, -1.0f);
    rank[c] = r;
  }
  // Phase 2: ranks ones … N−1 by filling the largest voids.
  bits = initial;
  energy = initialEnergy;
  for (int r = ones; r < N; ++r) {
    const int v = extreme(0, false);
    bits[v] = 1;
    update(v, 1.0f);
    rank[v] = r;
  }
  std::vector<float> table(N);
  for (int p = 0; p < N; ++p) table[p] = (float(rank[p]) + 0.5f) / float(N);
  return table;
}

}  // namespace

const std::vector<float>& blueNoiseTable() {
  static const std::vector<float> table = voidAndCluster(kBlueNoiseSize);
  return table;
}

}  // namespace scatterlab
