#include <cstdio>
#include <fstream>

#include "api/scatterlab.h"
#include "apps/commands.h"
#include "core/atomic_file.h"
#include "media/vdb.h"
#include "render/sample_view.h"

namespace scatterlab::cli {

Action addRender(CLI::App& app) {
  struct Opts {
    std::string scene, out, png, method, backend = "auto", stats, samplesPng, densityVdb,
                                         radianceVdb;
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
  c->add_option("--density-vdb", o->densityVdb,
                "Also write the density volume the method marched through as an OpenVDB file "
                "(FloatGrid 'density'; for Houdini, Blender); CPU methods");
  c->add_option("--radiance-vdb", o->radianceVdb,
                "Also write the source-radiance volume S as an OpenVDB file (Vec3SGrid "
                "'radiance'); CPU methods that build one (not exact)");
  c->add_flag("-q,--quiet", o->quiet, "No progress bar or summary");
  return [o]() {
    checkDistinctPaths({{"scene", o->scene},
                        {"--output", o->out},
                        {"--png", o->png},
                        {"--stats", o->stats},
                        {"--samples-png", o->samplesPng},
                        {"--density-vdb", o->densityVdb},
                        {"--radiance-vdb", o->radianceVdb}});
    const Scene scene = loadScene(o->scene, o->sets);
    auto method = createMethod(scene, o->method, o->backend);
    if (!method->ignoredKeys.empty()) {
      std::string list;
      for (const std::string& k : method->ignoredKeys)
        list += (list.empty() ? "'" : ", '") + k + "'";
      std::fprintf(
          stderr, "scatterlab: warning: ignoring %s (read by other methods, not '%s')\n",
          list.c_str(),
          (o->method.empty() ? scene.render.value("method", std::string("exact")) : o->method)
              .c_str());
    }
    // Refuse unwritable outputs before spending time on the render.
    checkWritablePath(o->out);
    if (!o->png.empty()) checkWritablePath(o->png);
    if (!o->stats.empty()) checkWritablePath(o->stats);
    if (!o->samplesPng.empty()) checkWritablePath(o->samplesPng);
    if (!o->densityVdb.empty()) checkWritablePath(o->densityVdb);
    if (!o->radianceVdb.empty()) checkWritablePath(o->radianceVdb);

    Progress progress("render", 1, !o->quiet);
    RenderResult r = method->render(scene, &progress);
    progress.restart("write", 1);

    PendingOutputs out;
    out.stage(o->out, [&](const std::string& tmp) { writeExr(r.image, tmp); });
    if (!o->png.empty())
      out.stage(o->png, [&](const std::string& tmp) { writePng(r.image, tmp, o->exposure); });
    if (!o->stats.empty())
      out.stageStream(o->stats, [&](std::ostream& f) { f << r.stats.toJson().dump(2) << "\n"; });
    if (!o->samplesPng.empty()) {
      if (r.samples.empty())
        throw ConfigError("--samples-png: method '" + r.stats.method +
                          "' used no radiance samples");
      const Image view = drawSamples(r.image, r.samples, scene.camera);
      out.stage(o->samplesPng, [&](const std::string& tmp) { writePng(view, tmp, o->exposure); });
    }
    const auto noVolume = [&](const char* option, const char* what) {
      return ConfigError(std::string(option) + ": method '" + r.stats.method + "' (" +
                         r.stats.backend + ") has no " + what +
                         " volume on the host; use a CPU method that builds one");
    };
    if (!o->densityVdb.empty()) {
      if (!r.density) throw noVolume("--density-vdb", "density");
      out.stage(o->densityVdb, [&](const std::string& tmp) { writeVdb(tmp, *r.density); });
    }
    if (!o->radianceVdb.empty()) {
      if (!r.radiance) throw noVolume("--radiance-vdb", "source-radiance");
      out.stage(o->radianceVdb, [&](const std::string& tmp) { writeVdb(tmp, *r.radiance); });
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
      for (const std::string* extra : {&o->samplesPng, &o->densityVdb, &o->radianceVdb})
        if (!extra->empty()) std::printf(", %s", extra->c_str());
      std::printf("\n");
    }
    return 0;
  };
}

}  // namespace scatterlab::cli
