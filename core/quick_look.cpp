#include "core/quick_look.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "core/error.h"
#include "core/grid.h"
#include "core/objects.h"
#include "core/scene.h"

namespace scatterlab {

namespace {

/// Columns (per axis) of the coarse grid whose optical depths set sigma_t.
constexpr int kColumns = 48;
/// The optical depth of the thick columns (their 90th percentile): dense enough to show shape
/// and self-shadowing, thin enough that the light reaches inside.
constexpr double kTargetDepth = 3.0;

/// sigma_t that gives the 90th percentile of the columns' optical depths along +z (the view
/// axis) kTargetDepth; 1 when the file holds no density.
double chooseSigmaT(const DensityModel& density, const Box& box) {
  const int nz = kColumns;
  DensityGrid grid(box, IVec3(kColumns, kColumns, nz));
  density.build(grid);
  const double dz = double(box.extent().z) / nz;
  std::vector<double> depths;
  for (int j = 0; j < kColumns; ++j)
    for (int i = 0; i < kColumns; ++i) {
      double sum = 0;
      for (int k = 0; k < nz; ++k) sum += double(grid.at(i, j, k));
      if (sum > 0 && std::isfinite(sum)) depths.push_back(sum * dz);
    }
  if (depths.empty()) return 1.0;
  const std::size_t rank = std::min(depths.size() - 1, std::size_t(0.9 * double(depths.size())));
  std::nth_element(depths.begin(), depths.begin() + std::ptrdiff_t(rank), depths.end());
  const double d = depths[rank];
  return d > 0 ? kTargetDepth / d : 1.0;
}

Json vec(const Vec3& v) {
  return Json::array({v.x, v.y, v.z});
}

}  // namespace

Json quickLookScene(const std::string& path, const std::string& densityType) {
  const std::filesystem::path file(path);
  Json doc = {
      {"medium",
       {{"density", {{"type", densityType}, {"file", file.filename().string()}}},
        {"resolution", 128},
        {"albedo", 0.9}}},
  };
  // The density alone, for its bounds and the optical depths.
  const Medium medium = parseMediumDocument(doc["medium"], file.parent_path());
  const Box box = medium.bounds;
  const Vec3 c = box.center();
  const float r = 0.5f * glm::length(box.extent());
  const float fov = 40.0f;
  const float distance = r / std::sin(glm::radians(fov / 2)) * 1.05f;
  // What the file makes impossible is said of the file, not of keys the user never wrote
  // (issue 37: denormal densities gave "'medium.sigma_t': value 2.14e+45 is beyond single
  // precision", a box of +-1e15 "'camera.position' ...").
  const auto g = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return std::string(b);
  };
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(double(c[a])) + double(distance) <= kMaxCoordinate / 10))
      throw IoError("'" + path + "': its volume spans [" + g(box.min.x) + ", " + g(box.max.x) +
                    "] x [" + g(box.min.y) + ", " + g(box.max.y) + "] x [" + g(box.min.z) + ", " +
                    g(box.max.z) +
                    "] in world units: too far out or too large to frame (a camera must stay "
                    "within +-1e14); write a scene for it with its own camera");
  const double sigmaT = chooseSigmaT(*medium.density, box);
  if (!(sigmaT <= 1e30))
    throw IoError("'" + path +
                  "': its densities are too small to render (the thick columns' "
                  "optical depth is " +
                  g(kTargetDepth / sigmaT) + " per unit of sigma_t, which would need sigma_t " +
                  g(sigmaT) + "); scale the grid's values, or write a scene with medium.sigma_t");
  doc["medium"]["sigma_t"] = sigmaT;
  doc["lights"] = Json::array({{{"type", "directional"},
                                {"direction", vec(glm::normalize(Vec3(0.45f, -1.0f, 0.6f)))},
                                {"irradiance", {12.0, 11.2, 10.0}}}});
  doc["camera"] = {{"position", vec(c + Vec3(0.0f, 0.15f * r, -distance))},
                   {"look_at", vec(c)},
                   {"up", {0, 1, 0}},
                   {"fov_y_deg", fov},
                   {"width", 320},
                   {"height", 240}};
  doc["background"] = {0.01, 0.012, 0.02};
  return doc;
}

}  // namespace scatterlab
