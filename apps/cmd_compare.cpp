#include <cstdio>

#include "api/scatterlab.h"
#include "apps/commands.h"

namespace scatterlab::cli {

Action addCompare(CLI::App& app) {
  struct Opts {
    std::string image, reference, diff;
    float diffScale = 0.0f;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* c = app.add_subcommand(
      "compare", "Error of an image against a reference: relative L2, relative L1, PSNR, max");
  c->add_option("image", o->image, "Image to judge (OpenEXR)")->required();
  c->add_option("reference", o->reference, "Reference image (OpenEXR)")->required();
  c->add_flag("--json", o->json, "Print JSON instead of text");
  c->add_option("--diff", o->diff,
                "Also write a PNG of |image - reference| (per channel), scaled so the largest "
                "difference is white unless --diff-scale is given");
  c->add_option("--diff-scale", o->diffScale, "Multiplier for --diff (default: 1/max)");
  return [o]() {
    const Image a = readExr(o->image), b = readExr(o->reference);
    const ImageError e = compareImages(a, b);
    if (!o->diff.empty()) {
      Image d(a.width(), a.height());
      for (size_t i = 0; i < d.pixels().size(); ++i)
        d.pixels()[i] = glm::abs(a.pixels()[i] - b.pixels()[i]);
      const float k =
          o->diffScale > 0 ? o->diffScale : (e.maxAbs > 0 ? float(1.0 / e.maxAbs) : 1.0f);
      for (Vec3& p : d.pixels()) p *= k;
      writePng(d, o->diff);
    }
    if (o->json) {
      Json j;
      j["image"] = o->image;
      j["reference"] = o->reference;
      j["width"] = a.width();
      j["height"] = a.height();
      j["rel_l2"] = e.relL2;
      j["rel_l1"] = e.relL1;
      j["psnr_db"] = std::isfinite(e.psnr) ? Json(e.psnr) : Json("inf");
      j["max_abs"] = e.maxAbs;
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      std::printf("relative L2 error: %.6g (%.3f%%)\n", e.relL2, 100 * e.relL2);
      std::printf("relative L1 error: %.6g (%.3f%%)\n", e.relL1, 100 * e.relL1);
      std::printf("PSNR (sRGB):       %.2f dB\n", e.psnr);
      std::printf("max abs error:     %.6g\n", e.maxAbs);
    }
    return 0;
  };
}

}  // namespace scatterlab::cli
