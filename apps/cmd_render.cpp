#include <sys/resource.h>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>

#include <glm/gtc/matrix_transform.hpp>

#include "api/scatterlab.h"
#include "apps/commands.h"
#include "apps/movie.h"
#include "core/atomic_file.h"
#include "core/quick_look.h"
#include "core/suggest.h"
#include "cpu/sample_view.h"
#include "media/vdb.h"

namespace scatterlab::cli {

namespace {

/// "A:B" (inclusive, 0 <= A <= B <= 999999, at most 100000 frames) -> {A, B}; nullopt when
/// malformed.
std::optional<std::pair<int, int>> parseFrames(const std::string& text) {
  const auto colon = text.find(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size()) return std::nullopt;
  const std::string a = text.substr(0, colon), b = text.substr(colon + 1);
  const auto digits = [](const std::string& s) {
    return s.size() <= 6 && s.find_first_not_of("0123456789") == std::string::npos;
  };
  if (!digits(a) || !digits(b)) return std::nullopt;
  const int first = std::stoi(a), last = std::stoi(b);
  if (first > last || last - first >= 100000) return std::nullopt;
  return std::make_pair(first, last);
}

/// "WxH" (or "WXH"; whole numbers in [1, Camera::kMaxSide], camera.width's and camera.height's
/// range) -> {W, H}; nullopt when malformed or out of range.
std::optional<std::pair<int, int>> parseResolution(const std::string& text) {
  const auto x = text.find_first_of("xX");
  if (x == std::string::npos) return std::nullopt;
  const std::string w = text.substr(0, x), h = text.substr(x + 1);
  const auto side = [](const std::string& s) -> int {
    if (s.empty() || s.size() > 6 || s.find_first_not_of("0123456789") != std::string::npos)
      return 0;
    const int v = std::stoi(s);
    return v <= Camera::kMaxSide ? v : 0;
  };
  const int width = side(w), height = side(h);
  if (width < 1 || height < 1) return std::nullopt;
  return std::make_pair(width, height);
}

/// Provenance and camera for the EXR header: scatterlab version, method, backend, device, scene
/// file, frame time; worldToCamera (glm::lookAt: right-handed, the camera looking down −z) and
/// worldToNDC (that times glm::perspective with the scene's vertical field of view and aspect,
/// near 0.01, far 1000: OpenGL clip space, x and y in [−1, 1] after the divide, y up).
ExrAttributes exrAttributes(const Scene& scene, const RenderStats& st, const std::string& file,
                            double time) {
  ExrAttributes a;
  a.strings = {{"scatterlab:version", version()},  {"scatterlab:method", st.method},
               {"scatterlab:backend", st.backend}, {"scatterlab:device", st.device},
               {"scatterlab:scene", file},         {"scatterlab:time", std::to_string(time)}};
  const Camera& c = scene.camera;
  const glm::mat4 view = glm::lookAt(c.position, c.lookAt, c.up);
  const glm::mat4 proj =
      glm::perspective(glm::radians(c.fovYDeg), float(c.width) / float(c.height), 0.01f, 1000.0f);
  const auto flat = [](const glm::mat4& m) {
    std::array<float, 16> f{};
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) f[size_t(4 * i + j)] = m[i][j];
    return f;
  };
  a.matrices = {{"worldToCamera", flat(view)}, {"worldToNDC", flat(proj * view)}};
  return a;
}

/// OUT.exr -> OUT.0007.exr: the frame number, 4 digits, before the extension.
/// `to` as a hard link to `from` (same bytes, nothing written), or a copy where the two are on
/// different file systems.
void linkOrCopy(const std::string& from, const std::string& to) {
  std::error_code ec;
  std::filesystem::remove(to, ec);
  std::filesystem::create_hard_link(from, to, ec);
  if (ec) std::filesystem::copy_file(from, to, std::filesystem::copy_options::overwrite_existing);
}

std::string framePath(const std::string& path, int frame) {
  if (path.empty() || frame < 0) return path;
  const std::filesystem::path p(path);
  char num[16];
  std::snprintf(num, sizeof num, ".%04d", frame);
  return (p.parent_path() / (p.stem().string() + num + p.extension().string())).string();
}

}  // namespace

Action addRender(CLI::App& app) {
  struct Opts {
    std::string scene, out, png, method, backend = "auto", stats, samplesPng, densityVdb,
                                         radianceVdb;
    std::vector<std::string> sets;
    // PNGs are previews: the default curve rolls glows off instead of clipping them to white
    // discs (EXR output stays linear whatever the curve).
    std::string frames, tonemap = "aces", resolution, movie;
    double fps = 24.0;
    float exposure = 0.0f;
    bool quiet = false, depth = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* c = app.add_subcommand("render", "Render a scene file to OpenEXR (and PNG)");
  c->add_option("scene", o->scene, "Scene file (JSON)")->required();
  c->add_option("-o,--output", o->out,
                "Output image; the extension decides the format: .exr (linear RGB float) or "
                ".png (tone-mapped sRGB, as --png)")
      ->required()
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            // A directory is left to checkWritablePath, which says so.
            return imageFormat(v).empty() && !std::filesystem::is_directory(v)
                       ? "'" + v + "' has an unknown extension: expected .exr or .png"
                       : "";
          },
          "FILE.exr|FILE.png"));
  c->add_option("--png", o->png, "Also write a tone-mapped sRGB PNG")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            return imageFormat(v) == "png" || std::filesystem::is_directory(v)
                       ? ""
                       : "'" + v + "' does not end in .png";
          },
          "FILE.png"));
  c->add_option("--method", o->method,
                "Rendering method (overrides render.method): exact, per-voxel, gradient, ... "
                "(scatterlab info --methods lists them)");
  c->add_option("--backend", o->backend, "cpu, gpu or auto (default: auto)")
      ->check(CLI::IsMember({"cpu", "gpu", "auto"}));
  c->add_option("--stats", o->stats, "Write render statistics (JSON)");
  c->add_option("--set", o->sets,
                "Override a scene key by dotted path, e.g. --set camera.width=640 (repeatable; "
                "VALUE parsed as JSON where it parses, else a string)")
      ->take_all()
      ->allow_extra_args(false);
  c->add_option("-r,--resolution", o->resolution,
                "Image size WxH, e.g. 640x480: the same as --set camera.width=W --set "
                "camera.height=H (not together with a --set of either)")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            return parseResolution(v) ? ""
                                      : "'" + v +
                                            "' is not a resolution: expected WxH with whole "
                                            "numbers from 1 to " +
                                            std::to_string(Camera::kMaxSide) + ", e.g. 640x480";
          },
          "WxH"));
  c->add_option("--exposure", o->exposure, "PNG exposure in stops (default 0)")
      ->check(exposureValidator());
  c->add_option("--tonemap", o->tonemap,
                "Tone curve of the PNG previews (--png, a .png -o, --samples-png): aces "
                "(Narkowicz, the default: highlights roll off), filmic (Hable) or linear "
                "(clamp at 1, the transform compare's PSNR uses); after --exposure; EXR output "
                "is always linear")
      ->check(CLI::IsMember({"linear", "filmic", "aces"}));
  c->add_option("--frames", o->frames,
                "Render frames A..B (inclusive) of an animation at time = frame / fps (light "
                "paths, procedural time, .sog sequences), writing OUT.{frame:04}.exr (and the "
                "same numbering for --png, --stats and the VDBs)")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            // Issue 37: the bound on frame numbers is said too (2147483646:2147483647 is two
            // frames, refused for its numbers, not its count).
            return parseFrames(v) ? ""
                                  : "'" + v +
                                        "' is not a frame range: expected A:B with integers "
                                        "0 <= A <= B <= 999999 and at most 100000 frames, "
                                        "e.g. 0:47";
          },
          "A:B"));
  CLI::Option* framesOption = c->get_option("--frames");
  c->add_option("--movie", o->movie,
                "With --frames: also encode the frames, tone-mapped as the PNG previews "
                "(--exposure, --tonemap), into a movie at --fps frames per second, by ffmpeg "
                "(on PATH, or $SCATTERLAB_FFMPEG): .mp4, .mkv or .mov (H.264), .webm (VP9) or "
                ".gif")
      ->needs(framesOption)
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            return movieFormat(v).empty()
                       ? "'" + v +
                             "' has no movie extension: expected .mp4, .mkv, .mov, .webm "
                             "or .gif"
                       : "";
          },
          "FILE.mp4|.mkv|.mov|.webm|.gif"));
  c->add_option("--fps", o->fps, "Frames per unit of scene time for --frames (default 24)")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            char* end = nullptr;
            const double x = std::strtod(v.c_str(), &end);
            return end != v.c_str() && *end == 0 && x > 0.0 && x <= 1e9
                       ? ""
                       : "'" + v + "' is not a frame rate in (0, 1e9]";
          },
          "FPS in (0, 1e9]"));
  c->add_option("--samples-png", o->samplesPng,
                "Also write a PNG of the radiance samples over the dimmed image, coloured by "
                "level (white initial, green/yellow/red finer); sample-based methods only");
  c->add_option("--density-vdb", o->densityVdb,
                "Also write the density volume the method marched through as an OpenVDB file "
                "(FloatGrid 'density'; for Houdini, Blender); CPU methods");
  c->add_option("--radiance-vdb", o->radianceVdb,
                "Also write the source-radiance volume S as an OpenVDB file (Vec3SGrid "
                "'radiance'); CPU methods that build one (not exact)");
  c->add_flag("--depth", o->depth,
              "Also write a Z channel in the EXR: the camera-space depth of the view ray's "
              "expected first interaction (opacity-weighted; +inf where the ray meets nothing); "
              "CPU methods that march the view ray (exact, per-voxel, gradient, rbf, nearest, "
              "adaptive)");
  c->add_flag("-q,--quiet", o->quiet, "No progress bar or summary");
  return [o]() {
    // The tool's own arguments before the scene: a misspelt method or a --set without '='
    // blames the flag (exit 2), not the scene file.
    if (!o->method.empty() && !methods().contains(o->method)) {
      std::string list;
      for (const std::string& n : methods().names()) list += (list.empty() ? "'" : ", '") + n + "'";
      throw UsageError("--method: unknown method '" + o->method + "'" +
                       didYouMean(o->method, methods().names()) + "; allowed: " + list);
    }
    checkSetOptions(o->sets);
    if (!o->resolution.empty()) {
      // -r is shorthand for two --set overrides: giving either key as well would leave one of
      // them silently unused.
      for (const std::string& a : o->sets) {
        const std::string key = a.substr(0, a.find('='));
        if (key == "camera" || key == "camera.width" || key == "camera.height")
          throw UsageError("--resolution " + o->resolution + " and --set " + a +
                           " both set the image size; give one of them");
      }
      const auto [w, h] = *parseResolution(o->resolution);
      o->sets.push_back("camera.width=" + std::to_string(w));
      o->sets.push_back("camera.height=" + std::to_string(h));
    }
    if (o->depth && imageFormat(o->out) != "exr")
      throw UsageError("--depth writes a Z channel, which needs an .exr output (-o " + o->out +
                       ")");
    checkDistinctPaths({{"scene", o->scene},
                        {"--output", o->out},
                        {"--png", o->png},
                        {"--stats", o->stats},
                        {"--samples-png", o->samplesPng},
                        {"--density-vdb", o->densityVdb},
                        {"--radiance-vdb", o->radianceVdb}});
    const ToneCurve curve = parseToneCurve(o->tonemap);
    Renderer renderer = Renderer::fromFile(o->scene, o->sets, o->method, o->backend);
    const Scene& scene = renderer.scene();
    if (!o->quiet && !volumeFileType(o->scene).empty())
      std::fprintf(stderr,
                   "scatterlab: note: '%s' is a volume without a scene: framed automatically "
                   "(camera on the -z side, one directional light, medium.sigma_t = %.3g for an "
                   "optical depth of 3 through its thick parts); change any key with --set "
                   "(docs/scene-format.md, \"Rendering a volume file without a scene\")\n",
                   o->scene.c_str(), double(scene.medium.sigmaT));
    const Method& method = renderer.method();
    if (!method.ignoredKeys.empty()) {
      std::string list;
      for (const std::string& k : method.ignoredKeys)
        list += (list.empty() ? "'" : ", '") + k + "'";
      std::fprintf(stderr, "scatterlab: warning: ignoring %s (read by other methods, not '%s')\n",
                   list.c_str(),
                   (o->method.empty() ? scene.render.value("method", std::string(kDefaultMethod))
                                      : o->method)
                       .c_str());
    }
    // The frames: one unnumbered render, or A..B of a sequence. Every frame's scene is checked
    // (light paths) before the first render, so a bad key fails before anything is written.
    std::vector<int> frames{-1};
    if (!o->frames.empty()) {
      const auto [first, last] = *parseFrames(o->frames);
      frames.clear();
      for (int f = first; f <= last; ++f) frames.push_back(f);
      sceneAtTime(renderer.document(), 0.0);
    }
    const auto timeOf = [&](int f) { return f / o->fps; };
    // Refuse unwritable outputs before spending time on the render.
    for (int f : frames)
      for (const std::string* p :
           {&o->out, &o->png, &o->stats, &o->samplesPng, &o->densityVdb, &o->radianceVdb})
        if (!p->empty()) checkWritablePath(framePath(*p, f));
    // --movie: ffmpeg found, the movie writable and a directory for its frames, before any
    // render; the frames go there as PNGs and are encoded before anything is committed.
    std::string ffmpeg;
    std::optional<TempDir> movieFrames;
    if (!o->movie.empty()) {
      ffmpeg = findFfmpeg();
      checkWritablePath(o->movie);
      movieFrames.emplace("scatterlab-movie");
    }

    const bool sequence = frames.size() > 1 || frames[0] >= 0;
    Progress progress(sequence ? "frames" : "render", sequence ? (long long)frames.size() : 1,
                      !o->quiet);
    // One set of pending outputs for the whole sequence: on any error no frame is left.
    PendingOutputs out;
    std::vector<RenderStats> summaries;  // per frame, for the summary line
    for (int f : frames) {
      if (f >= 0) renderer.setTime(timeOf(f));
      RenderResult r = renderer.render(sequence ? nullptr : &progress);
      if (f >= 0) r.stats.extra["frame"] = f;
      // Peak resident memory of the process so far (MiB): scene, volumes and the method's
      // buffers, the tool running one method.
      rusage ru{};
      if (getrusage(RUSAGE_SELF, &ru) == 0)
        r.stats.extra["peak_host_mib"] = double(ru.ru_maxrss) / 1024.0;
      if (o->depth && r.image.depth().size() != r.image.pixels().size())
        throw ConfigError("--depth: method '" + r.stats.method + "' (" + r.stats.backend +
                          ") records no depth; use --backend cpu with exact, per-voxel, "
                          "gradient, rbf, nearest or adaptive");
      if (!o->depth) r.image.depth().clear();
      if (!sequence) progress.restart("write", 1);
      const Scene& frameScene = renderer.scene();
      // The frame's PNG is encoded once: a movie frame is a link to (or a copy of) the PNG
      // written for OUT or --png when there is one.
      std::string pngWritten;
      const auto writeFramePng = [&](const std::string& tmp) {
        writePng(r.image, tmp, o->exposure, curve);
        pngWritten = tmp;
      };
      out.stage(framePath(o->out, f), [&](const std::string& tmp) {
        if (imageFormat(o->out) == "png")
          writeFramePng(tmp);
        else
          writeExr(r.image, tmp, exrAttributes(frameScene, r.stats, o->scene, renderer.time()));
      });
      if (!o->png.empty())
        out.stage(framePath(o->png, f), [&](const std::string& tmp) {
          if (pngWritten.empty())
            writeFramePng(tmp);
          else
            linkOrCopy(pngWritten, tmp);
        });
      if (movieFrames) {
        const std::string frame = movieFramePath(movieFrames->path(), int(summaries.size()));
        if (pngWritten.empty())
          writePng(r.image, frame, o->exposure, curve);
        else
          linkOrCopy(pngWritten, frame);
      }
      if (!o->stats.empty())
        out.stageStream(framePath(o->stats, f),
                        [&](std::ostream& file) { file << r.stats.toJson().dump(2) << "\n"; });
      if (!o->samplesPng.empty()) {
        if (r.samples.empty())
          throw ConfigError("--samples-png: method '" + r.stats.method +
                            "' used no radiance samples");
        const Image view = drawSamples(r.image, r.samples, frameScene.camera);
        out.stage(framePath(o->samplesPng, f),
                  [&](const std::string& tmp) { writePng(view, tmp, o->exposure, curve); });
      }
      const auto noVolume = [&](const char* option, const char* what) {
        return ConfigError(std::string(option) + ": method '" + r.stats.method + "' (" +
                           r.stats.backend + ") has no " + what +
                           " volume on the host; use a CPU method that builds one");
      };
      if (!o->densityVdb.empty()) {
        if (!r.density) throw noVolume("--density-vdb", "density");
        out.stage(framePath(o->densityVdb, f), [&](const std::string& tmp) {
          writeVdb(tmp, *r.density, "density",
                   {frameScene.medium.sigmaT, frameScene.medium.albedo});
        });
      }
      if (!o->radianceVdb.empty()) {
        if (!r.radiance) throw noVolume("--radiance-vdb", "source-radiance");
        out.stage(framePath(o->radianceVdb, f), [&](const std::string& tmp) {
          writeVdb(tmp, *r.radiance, "radiance",
                   {frameScene.medium.sigmaT, frameScene.medium.albedo,
                    "world units; radiance S per unit solid angle"});
        });
      }
      if (sequence) {
        progress.advance();
        if (!o->quiet)
          std::fprintf(stderr, "\rframe %04d: %.1f ms%s\n", f, r.stats.totalMs(),
                       r.stats.extra.value("density_reused", false) ? " (density reused)" : "");
      }
      summaries.push_back(std::move(r.stats));
    }
    if (movieFrames)
      out.stage(o->movie, [&](const std::string& tmp) {
        encodeMovie(ffmpeg, movieFrames->path(), int(summaries.size()), o->fps,
                    movieFormat(o->movie), tmp);
      });
    out.commit();
    if (!o->quiet) {
      const RenderStats& st = summaries.back();
      double total = 0.0;
      for (const RenderStats& r : summaries) total += r.totalMs();
      std::printf("%s (%s, %s): %dx%d", st.method.c_str(), st.backend.c_str(), st.device.c_str(),
                  st.width, st.height);
      if (sequence)
        std::printf(", %zu frames in %.1f ms (%.1f ms per frame)\n", summaries.size(), total,
                    total / summaries.size());
      else
        std::printf(" in %.1f ms\n", total);
      if (st.extra.contains("backend_choice"))
        std::printf("%s\n", st.extra["backend_choice"].get<std::string>().c_str());
      if (st.extra.value("voxels_instead", false)) {
        // Under spot lights only, the voxels traced are at most those the cones reach.
        const long long occupied = st.extra["occupied_voxels"].get<long long>();
        const std::string lit =
            st.extra.contains("lit_voxels")
                ? " (at most " +
                      std::to_string(std::min(occupied, st.extra["lit_voxels"].get<long long>())) +
                      " of them inside the spot cones)"
                : "";
        std::printf(
            "rendered as per-voxel renders it: the medium's %lld occupied voxels%s cost less "
            "to trace than the method's samples (render.voxel_switch; 0 turns it off)\n",
            occupied, lit.c_str());
      }
      const int f0 = frames.front(), f1 = frames.back();
      const auto shown = [&](const std::string& p) {
        return sequence ? framePath(p, f0) + " .. " + framePath(p, f1) : p;
      };
      std::printf("wrote %s", shown(o->out).c_str());
      for (const std::string* extra :
           {&o->png, &o->stats, &o->samplesPng, &o->densityVdb, &o->radianceVdb})
        if (!extra->empty()) std::printf(", %s", shown(*extra).c_str());
      if (!o->movie.empty()) std::printf(", %s", o->movie.c_str());
      std::printf("\n");
    }
    return 0;
  };
}

}  // namespace scatterlab::cli
