// The experiment's reference images: keyed by everything that determines them, rendered (or
// taken from a run that renders the same configuration) once, cached in memory and on disk
// under DIR/references/, and reused from disk by a resumed experiment.

#include <cstdio>
#include <filesystem>

#include "core/scene.h"
#include "experiment/detail.h"

namespace scatterlab::detail {

namespace fs = std::filesystem;

Reference& ReferenceCache::get(const RunSpec& r, const MethodSpec& ref, const RenderResult* seed) {
  std::vector<std::string> sets = r.refSets;  // the files the reference's scene names
  sets.insert(sets.end(), ref.sets.begin(), ref.sets.end());
  Json key = {{"scene", sceneHash(r.sceneSpec->file, sets)},
              {"sets", r.refSets},
              {"lights", r.refLights ? Json(*r.refLights) : Json()},
              {"method", ref.method},
              {"backend", ref.backend},
              {"ref_sets", ref.sets}};
  if (ref.converge) key["converge"] = kReferenceTolerance;
  const std::string base = "references/" + ref.name + "-" + stableHash(key.dump());
  auto it = cache_.find(base);
  if (it != cache_.end()) return it->second;
  Reference& rc = cache_[base];
  rc.name = ref.name;
  rc.file = base + ".png";
  try {
    if (fs::exists(out_.path(base + ".exr")) && fs::exists(out_.path(base + ".json"))) {
      rc.image = readExr(out_.path(base + ".exr"));
      rc.check = readJsonFile(out_.path(base + ".json")).value("convergence", Json());
      rc.ok = true;
      out_.log("reference " + base + ": reused from disk");
    } else {
      render(r, ref, seed, key, base, rc);
    }
  } catch (const std::exception& e) {
    rc.error = e.what();
    out_.log("reference " + base + " FAILED: " + rc.error);
  }
  return rc;
}

void ReferenceCache::render(const RunSpec& r, const MethodSpec& ref, const RenderResult* seed,
                            const Json& key, const std::string& base, Reference& rc) {
  std::vector<std::string> sets = r.refSets;
  sets.insert(sets.end(), ref.sets.begin(), ref.sets.end());
  RenderResult rr;
  if (seed) {
    rr = *seed;
  } else {
    const Scene scene = buildRunScene(r.sceneSpec->file, sets, r.refLights);
    auto method = createMethod(scene, ref.method, ref.backend);
    if (!method->ignoredKeys.empty()) {
      // The scenes' own method settings do not apply to the reference: noted once per set in
      // log.txt. Not a warning on the terminal: a reference is another method by design, so
      // every shipped config (fig3's scene sets render.sampler) would print one.
      std::string list;
      for (const std::string& k : method->ignoredKeys) list += (list.empty() ? "" : ", ") + k;
      if (warned_.insert(ref.name + ": " + list).second)
        out_.log("reference " + ref.name + " ignores " + list + " (read by other methods)");
    }
    rr = ref.converge ? renderConverged(scene, ref, rc.check) : method->render(scene, nullptr);
  }
  writeExr(rr.image, out_.path(base + ".exr"));
  writePng(rr.image, out_.path(base + ".png"), plan_.exposure);
  Json j = rr.stats.toJson();
  j["scene"] = r.sceneSpec->file;
  j["sets"] = sets;
  j["key"] = key;
  if (!rc.check.is_null()) {
    rc.check["file"] = base + ".exr";
    j["convergence"] = rc.check;
  }
  writeText(out_.path(base + ".json"), j.dump(2) + "\n");
  rc.image = std::move(rr.image);
  rc.ok = true;
  out_.log("reference " + base + (seed ? ": taken from run " + r.id : ": rendered") + " in " +
           fmt(rr.stats.totalMs(), "%.1f") + " ms" +
           (rc.check.is_null()
                ? std::string()
                : "; halving its steps changes it by " +
                      fmt(100 * rc.check["change_rel_l2"].get<double>(), "%.3f") + "% relative L2" +
                      (rc.check["refined"].get<bool>() ? ", refined to 1/4 voxel" : "")));
  if (console_)
    std::fprintf(console_, "%sreference %-30s %9.1f ms\n", clearLine_ ? "\r\033[K" : "",
                 ref.name.c_str(), rr.stats.totalMs());
}

RenderResult ReferenceCache::renderConverged(const Scene& scene, const MethodSpec& ref,
                                             Json& check) {
  // Half a voxel: the reference must resolve what the methods' one-voxel volumes cannot; the
  // halving check says whether that is fine enough for this scene.
  const double voxel = scene.medium.voxelSize(), h = 0.5 * voxel;
  const auto renderAt = [&](double step) {
    Scene s = scene;
    s.render["march_step"] = step;
    s.render["delta1"] = step;
    return createMethod(s, ref.method, ref.backend)->render(s, nullptr);
  };
  RenderResult coarse = renderAt(h), fine = renderAt(0.5 * h);
  const double change = compareImages(coarse.image, fine.image).relL2;
  const bool passed = change < kReferenceTolerance;
  check = {{"voxel", voxel},
           {"step", passed ? h : 0.5 * h},
           {"step_voxels", passed ? 0.5 : 0.25},
           {"check_step", 0.5 * h},
           {"change_rel_l2", change},
           {"threshold", kReferenceTolerance},
           {"passed", passed},
           {"refined", !passed},
           {"time_ms", coarse.stats.totalMs() + fine.stats.totalMs()}};
  return passed ? std::move(coarse) : std::move(fine);
}

}  // namespace scatterlab::detail
