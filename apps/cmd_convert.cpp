#include <cstdio>

#include "api/scatterlab.h"
#include "apps/commands.h"
#include "core/atomic_file.h"

namespace scatterlab::cli {

Action addConvert(CLI::App& app) {
  struct Opts {
    std::string in, out;
    // The same defaults as render's PNGs: exposure 0, the aces curve.
    std::string tonemap = "aces";
    float exposure = 0.0f;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* c = app.add_subcommand(
      "convert",
      "Write an 8-bit sRGB PNG of a linear OpenEXR image with render's PNG transform "
      "(--exposure, then --tonemap, then the sRGB encoding): the PNG render --png would have "
      "written beside the EXR");
  c->add_option("input", o->in, "Linear OpenEXR image (R, G, B; A and Z are not used)")->required();
  c->add_option("output", o->out, "PNG to write")
      ->required()
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            // A directory is left to checkWritablePath, which says so.
            if (imageFormat(v) == "png" || std::filesystem::is_directory(v)) return "";
            return "'" + v + "' does not end in .png: convert writes PNG only" +
                   (imageFormat(v) == "exr" ? " (an EXR is already the linear image)" : "");
          },
          "FILE.png"));
  c->add_option("--exposure", o->exposure, "Exposure in stops before the tone curve (default 0)")
      ->check(exposureValidator());
  c->add_option("--tonemap", o->tonemap,
                "Tone curve, as render --tonemap: aces (the default, as render's PNGs), filmic "
                "or linear (clamp at 1)")
      ->check(CLI::IsMember({"linear", "filmic", "aces"}));
  return [o]() {
    checkDistinctPaths({{"input", o->in}, {"output", o->out}});
    const ToneCurve curve = parseToneCurve(o->tonemap);
    refusePng(o->in, "input", "convert reads");
    const Image img = readExr(o->in);
    if (img.pixels().empty())
      throw IoError("input '" + o->in + "' has no pixels (0x0): there is nothing to convert");
    // writePng would show NaN as black and inf as white: a broken image is said, not hidden.
    if (const NonFiniteValues bad = countNonFinite(img, /*withAlpha=*/false); bad.any())
      throw IoError("input '" + o->in + "' has " + bad.describe() +
                    "; convert needs finite pixels (scatterlab info " + o->in + " counts them)");
    checkWritablePath(o->out);
    writePng(img, o->out, o->exposure, curve);
    std::printf("wrote %s (%dx%d, exposure %g, %s)\n", o->out.c_str(), img.width(), img.height(),
                double(o->exposure), o->tonemap.c_str());
    return 0;
  };
}

}  // namespace scatterlab::cli
