#include <cstdio>
#include <fstream>

#include "api/scatterlab.h"
#include "apps/commands.h"
#include "core/atomic_file.h"
#include "render/sample_view.h"

namespace scatterlab::cli {

Action addRender(CLI::App& app) {
  struct Opts {
    std::string scene, out, png, method, backend = "auto", stats, samplesPng;
    std::vector<std::string> sets;
    float exposure = 0.0f;
    bool quiet = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* c = app.add_subcommand("render", "Render a scene file to OpenEXR (and PNG)");
  c->add_option("scene", o->scene, "Scene file (JSON)")->required();
  c->add_option("-o,--output", o->out, "Output OpenEXR image (linear RGB float)")->required();
  c->add_option("--png", o->png, "Also write a tone-mapped sRGB PNG");
  c->add_option("--method", o->method,
                "Rendering method (overrides render.method): exact, per-voxel, ...");
  c->add_option("--backend", o->backend, "cpu, gpu or auto (default: auto)")
      ->check(CLI::IsMember({"cpu", "gpu", "auto"}));
  c->add_option("--stats", o->stats, "Write render statistics (JSON)");
  c->add_option("--set", o->sets,
                "Override a scene key by dotted path, e.g. --set camera.width=640 (repeatable; "
                "VALUE parsed as JSON where it parses, else a string)")
      ->take_all()
      ->allow_extra_args(false);
  c->add_option("--exposure", o->exposure, "PNG exposure in stops (default 0)");
  c->add_option("--samples-png", o->samplesPng,
                "Also write a PNG of the radiance samples over the dimmed image, coloured by "
                "level (white initial, green/yellow/red finer); sample-based methods only");
  c->add_flag("-q,--quiet", o->quiet, "No progress bar or summary");
  return [o]() {
    const Scene scene = loadScene(o->scene, o->sets);
    auto method = createMethod(scene, o->method, o->backend);
    // Refuse unwritable outputs before spending time on the render.
    checkWritablePath(o->out);
    if (!o->png.empty()) checkWritablePath(o->png);
    if (!o->stats.empty()) checkWritablePath(o->stats);
    if (!o->samplesPng.empty()) checkWritablePath(o->samplesPng);

    Progress progress("render", 1, !o->quiet);
    RenderResult r = method->render(scene, &progress);
    progress.restart("write", 1);

    PendingOutputs out;
    out.stage(o->out, [&](const std::string& tmp) { writeExr(r.image, tmp); });
    if (!o->png.empty())
      out.stage(o->png, [&](const std::string& tmp) { writePng(r.image, tmp, o->exposure); });
    if (!o->stats.empty())
      out.stage(o->stats, [&](const std::string& tmp) {
        std::ofstream f(tmp);
        f << r.stats.toJson().dump(2) << "\n";
        if (!f) throw IoError("cannot write stats '" + o->stats + "'");
      });
    if (!o->samplesPng.empty()) {
      if (r.samples.empty())
        throw ConfigError("--samples-png: method '" + r.stats.method +
                          "' used no radiance samples");
      const Image view = drawSamples(r.image, r.samples, scene.camera);
      out.stage(o->samplesPng, [&](const std::string& tmp) { writePng(view, tmp, o->exposure); });
    }
    out.commit();
    if (!o->quiet) {
      std::printf("%s (%s, %s): %dx%d in %.1f ms\n", r.stats.method.c_str(),
                  r.stats.backend.c_str(), r.stats.device.c_str(), r.stats.width, r.stats.height,
                  r.stats.totalMs());
      if (r.stats.extra.contains("backend_choice"))
        std::printf("%s\n", r.stats.extra["backend_choice"].get<std::string>().c_str());
      std::printf("wrote %s", o->out.c_str());
      if (!o->png.empty()) std::printf(", %s", o->png.c_str());
      if (!o->stats.empty()) std::printf(", %s", o->stats.c_str());
      if (!o->samplesPng.empty()) std::printf(", %s", o->samplesPng.c_str());
      std::printf("\n");
    }
    return 0;
  };
}

}  // namespace scatterlab::cli
