#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "api/scatterlab.h"
#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/metrics.h"
#include "experiment/error_map.h"

namespace scatterlab::cli {

namespace {

/// A measure as JSON: NaN (no mask, or a mask that keeps nothing) as null, +inf as "inf".
Json number(double v) {
  if (std::isnan(v)) return Json(nullptr);
  if (std::isinf(v)) return Json(v > 0 ? "inf" : "-inf");
  return Json(v);
}

}  // namespace

Action addCompare(CLI::App& app) {
  struct Opts {
    std::string image, reference, diff, scene;
    std::vector<std::string> sets;
    float diffScale = 0.0f;
    double maskRadius = -1.0;
    bool json = false, diffSigned = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* c = app.add_subcommand(
      "compare",
      "Error of an image against a reference: relative L2 (the headline), relative L1, PSNR, "
      "max abs error, the share of visibly wrong pixels and, with --scene, relative L2 with the "
      "pixels next to each light masked (definitions: docs/metrics.md)");
  c->add_option("image", o->image, "Image to judge (OpenEXR)")->required();
  c->add_option("reference", o->reference, "Reference image (OpenEXR)")->required();
  c->add_flag("--json", o->json, "Print JSON instead of text");
  CLI::Option* diff =
      c->add_option("--diff", o->diff,
                    "Also write a PNG of |image - reference| (per channel), scaled so the largest "
                    "difference is white unless --diff-scale is given");
  CLI::Option* diffScale =
      c->add_option("--diff-scale", o->diffScale, "Multiplier for --diff (default: 1/max)")
          ->check(
              // Issue 37: nan, -inf, -1, 0 and '' fell back to the default silently, inf saturated
              // the map: a finite number > 0 (in single precision), or the option left out.
              [](const std::string& v) -> std::string {
                char* end = nullptr;
                const double k = std::strtod(v.c_str(), &end);
                return end != v.c_str() && *end == 0 && std::isfinite(k) && float(k) > 0 &&
                               k <= double(std::numeric_limits<float>::max())
                           ? ""
                           : "expected a finite multiplier > 0, got '" + v + "'";
              },
              "S > 0");
  c->add_flag("--diff-signed", o->diffSigned,
              "Make --diff a signed error map instead (the experiment gallery's): per pixel the "
              "mean over channels of the difference after the PNG transform, red where the "
              "image is brighter, blue where darker, full colour at +-0.1; its colour scale "
              "below the map")
      ->needs(diff)
      ->excludes(diffScale);
  CLI::Option* scene = c->add_option(
      "--scene", o->scene,
      "The scene the images show (JSON): its camera and point/spot lights give the masked "
      "relative L2. Without --scene the masked relative L2 is not computed or printed");
  c->add_option("--set", o->sets,
                "Override a key of --scene, as for render (repeatable); give the overrides the "
                "images were rendered with")
      ->take_all()
      ->allow_extra_args(false)
      ->needs(scene);
  c->add_option("--mask-radius", o->maskRadius,
                "Radius K in pixels of the disc masked around each light's projection (default: "
                "1% of the image diagonal, at least 2 px); needs --scene")
      ->check(
          [](const std::string& v) -> std::string {
            char* end = nullptr;
            const double k = std::strtod(v.c_str(), &end);
            return end != v.c_str() && *end == 0 && std::isfinite(k) && k >= 0
                       ? ""
                       : "expected a number of pixels >= 0, got '" + v + "'";
          },
          "K >= 0")
      ->needs(scene);
  return [o]() {
    checkDistinctPaths({{"image", o->image}, {"--diff", o->diff}});
    checkDistinctPaths({{"reference", o->reference}, {"--diff", o->diff}});
    refusePng(o->image, "image", "compare needs");
    refusePng(o->reference, "reference", "compare needs");
    const Image a = readExr(o->image), b = readExr(o->reference);
    // compareImages refuses them too; here the message names the file.
    for (const auto& [file, img] : {std::pair{&o->image, &a}, std::pair{&o->reference, &b}}) {
      if (img->pixels().empty())
        throw IoError("image '" + *file + "' has no pixels (0x0): there is nothing to compare");
      if (const NonFiniteValues bad = countNonFinite(*img, /*withAlpha=*/false); bad.any())
        throw IoError("image '" + *file + "' has " + bad.describe() +
                      "; compare needs finite pixels (scatterlab info " + *file + " counts them)");
    }
    // Everything is read and checked before the --diff PNG is written: no partial output.
    std::optional<LightMask> mask;
    if (!o->scene.empty()) {
      const Scene s = loadScene(o->scene, o->sets);
      mask = lightMask(s, o->maskRadius >= 0 ? o->maskRadius
                                             : defaultMaskRadius(s.camera.width, s.camera.height));
    }
    const ImageError e = mask ? compareImages(a, b, *mask) : compareImages(a, b);
    // The unsigned map's multiplier: white at |difference| = 1/k.
    const float k = o->diffScale > 0 ? o->diffScale : (e.maxAbs > 0 ? float(1.0 / e.maxAbs) : 1.0f);
    if (!o->diff.empty()) {
      checkWritablePath(o->diff);
      if (o->diffSigned) {
        writePng(signedErrorMapWithScale(a, b), o->diff);
      } else {
        Image d(a.width(), a.height());
        for (size_t i = 0; i < d.pixels().size(); ++i)
          d.pixels()[i] = glm::abs(a.pixels()[i] - b.pixels()[i]);
        for (Vec3& p : d.pixels()) p *= k;
        writePng(d, o->diff);
      }
    }
    if (o->json) {
      Json j;
      j["image"] = o->image;
      j["reference"] = o->reference;
      j["width"] = a.width();
      j["height"] = a.height();
      j["rel_l2"] = number(e.relL2);
      j["rel_l1"] = number(e.relL1);
      j["psnr_db"] = number(e.psnr);
      j["max_abs"] = number(e.maxAbs);
      j["visibly_wrong"] = e.visiblyWrong;
      j["visible_threshold"] = kVisibleThreshold;
      if (!o->diff.empty()) {
        if (o->diffSigned)
          j["diff"] = {{"file", o->diff},
                       {"signed", true},
                       {"full_scale", kErrorMapFull},
                       {"units", "mean sRGB channel difference (PNG transform, exposure 0)"}};
        else
          j["diff"] = {{"file", o->diff},
                       {"signed", false},
                       {"multiplier", k},
                       {"white_at", 1.0 / double(k)},
                       {"units", "linear, per channel"}};
      }
      if (mask) {
        j["masked_rel_l2"] = number(e.maskedRelL2);
        j["mask_radius_px"] = e.maskRadius;
        j["masked_lights"] = e.maskedLights;
        j["masked_pixels"] = mask->maskedPixels();
      }
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      std::printf("relative L2 error: %.6g (%.3f%%)\n", e.relL2, 100 * e.relL2);
      std::printf("relative L1 error: %.6g (%.3f%%)\n", e.relL1, 100 * e.relL1);
      std::printf("PSNR (sRGB):       %.2f dB\n", e.psnr);
      std::printf("max abs error:     %.6g\n", e.maxAbs);
      std::printf(
          "visibly wrong:     %.4f%% of pixels (some channel off by > %.2f after the PNG "
          "transform)\n",
          100 * e.visiblyWrong, kVisibleThreshold);
      if (mask) {
        if (std::isnan(e.maskedRelL2))
          std::printf("masked rel. L2:    n/a (the mask covers every pixel)\n");
        else
          std::printf(
              "masked rel. L2:    %.6g (%.3f%%), %zu px within %.3g px of %d light%s "
              "excluded\n",
              e.maskedRelL2, 100 * e.maskedRelL2, mask->maskedPixels(), e.maskRadius,
              e.maskedLights, e.maskedLights == 1 ? "" : "s");
      }
      if (!o->diff.empty()) {
        if (o->diffSigned)
          std::printf(
              "signed diff:       %s: red = image brighter, blue = darker, full colour at a mean "
              "sRGB channel difference of +-%g (PNG transform, exposure 0); scale bar below\n",
              o->diff.c_str(), kErrorMapFull);
        else
          std::printf("diff:              %s: |image - reference| x %g, white at %g (linear)\n",
                      o->diff.c_str(), double(k), 1.0 / double(k));
      }
    }
    return 0;
  };
}

}  // namespace scatterlab::cli
