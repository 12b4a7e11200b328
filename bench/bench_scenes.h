#pragma once
/// Scene documents the benchmarks share.

#include <cmath>

#include "api/scatterlab.h"

namespace scatterlab::bench {

/// `doc` with `lights` point lights: its first light, then copies of it (intensity shared out)
/// on a ring around the medium box's centre, 0.45 of the box out and 0.3 of it up.
inline void addLampRing(Json& doc, int lights) {
  const Json first = doc["lights"][0];
  const Json& b = doc["medium"]["bounds"];
  const Vec3 lo(b["min"][0].get<float>(), b["min"][1].get<float>(), b["min"][2].get<float>());
  const Vec3 hi(b["max"][0].get<float>(), b["max"][1].get<float>(), b["max"][2].get<float>());
  const Vec3 centre = 0.5f * (lo + hi), ext = hi - lo;
  for (int l = 1; l < lights; ++l) {
    Json light = first;
    const float a = 6.2831853f * float(l) / float(lights);
    light["position"] = {centre.x + 0.45f * ext.x * std::cos(a), centre.y + 0.3f * ext.y,
                         centre.z + 0.45f * ext.z * std::sin(a)};
    doc["lights"].push_back(light);
  }
  if (lights > 1)
    for (Json& light : doc["lights"])
      if (light.contains("intensity"))
        for (Json& v : light["intensity"]) v = v.get<double>() / lights;
}

}  // namespace scatterlab::bench
