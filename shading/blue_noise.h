#pragma once
/// The blue-noise table of `jittered-march`'s jitter "blue-noise" (shading/screen_march.h),
/// read by its CPU variant and uploaded by its GPU variant.

#include <vector>

namespace scatterlab {

/// Side of the tileable blue-noise table.
inline constexpr int kBlueNoiseSize = 64;

/// A kBlueNoiseSize² tileable blue-noise table (row-major), values (rank + ½)/N in (0, 1),
/// each rank once: Ulichney's void-and-cluster (1993) on the torus, Gaussian energy σ = 1.5,
/// initial pattern of N/10 points from a fixed seed, so the table is the same on every run and
/// machine. Built once on first use (a few ms).
const std::vector<float>& blueNoiseTable();

}  // namespace scatterlab
