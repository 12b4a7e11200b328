/// scatterlab._core: the Python binding (pybind11 + numpy). The package python/scatterlab
/// re-exports it; docs/python.md is the user's reference. Images are float32 (H, W, 3) arrays,
/// row 0 at the top; volumes are (nz, ny, nx[, 3]) arrays indexed [k, j, i] over the medium box.
/// The GIL is released while scenes load, methods render and images are compared.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <optional>
#include <thread>

#include "api/scatterlab.h"
#include "core/image.h"
#include "core/limits.h"
#include "core/metrics.h"
#include "core/quick_look.h"
#include "core/stages.h"

namespace py = pybind11;
using namespace scatterlab;

namespace {

/// json.dumps with numpy scalars and arrays (anything with tolist(): np.float32(0.5),
/// np.array([1, 2, 3])) taken as the plain numbers and lists they hold, and without NaN or inf
/// (not JSON: they used to reach nlohmann's parser and surface as a bare RuntimeError
/// "[json.exception.parse_error.101]"); `what` names the value.
std::string dumps(const py::handle& obj, const std::string& what) {
  // Made per call: a static py::object would be released after the interpreter finalised.
  const py::object toList = py::cpp_function([](const py::object& o) -> py::object {
    if (py::hasattr(o, "tolist")) return o.attr("tolist")();
    throw py::type_error("Object of type " +
                         py::str(py::type::of(o).attr("__name__")).cast<std::string>() +
                         " is not JSON serializable");
  });
  try {
    return py::str(py::module_::import("json").attr("dumps")(obj, py::arg("default") = toList,
                                                             py::arg("allow_nan") = false));
  } catch (py::error_already_set& e) {
    if (!e.matches(PyExc_ValueError)) throw;
    throw ConfigError(what + ": " + std::string(py::str(e.value())) +
                      " (NaN and infinity are not JSON numbers; scene values must be finite)");
  }
}

Json toJson(const py::handle& obj) {
  return parseJson(dumps(obj, "scene"), "the scene dict");
}

/// The scene's lights as the scene format writes them (lightJson).
Json lightsJson(const std::vector<Light>& lights) {
  Json out = Json::array();
  for (const Light& l : lights) out.push_back(lightJson(l));
  return out;
}

py::object fromJson(const Json& j) {
  return py::module_::import("json").attr("loads")(j.dump());
}

/// `overrides`: None, a dict {"camera.width": 64, ...} (values JSON-encoded) or a list of
/// "key=VALUE" strings, as --set.
std::vector<std::string> assignments(const py::object& overrides) {
  std::vector<std::string> out;
  if (overrides.is_none()) return out;
  if (py::isinstance<py::dict>(overrides)) {
    for (auto [k, v] : overrides.cast<py::dict>()) {
      const std::string key = py::str(k).cast<std::string>();
      out.push_back(key + "=" + dumps(v, "overrides['" + key + "']"));
    }
    return out;
  }
  if (py::isinstance<py::str>(overrides))
    throw ConfigError("overrides: expected a dict or a list of 'key=VALUE' strings, got a str");
  for (const py::handle& a : overrides) out.push_back(py::str(a).cast<std::string>());
  return out;
}

/// Native work in flight on any thread (GilReleased scopes), and whether the interpreter is on
/// its way out (set by the module's atexit hook, waitForNativeWork()).
std::atomic<int> nativeWork{0};
std::atomic<bool> exiting{false};

/// Parks the calling thread for good: the process is exiting, and its exit ends the thread.
[[noreturn]] void park() {
  for (;;) std::this_thread::sleep_for(std::chrono::hours(1));
}

/// The GIL released for a scope, as py::gil_scoped_release, for the native work of a call.
/// Daemon threads still rendering when the interpreter exits (issue 37): Python ends such a
/// thread by pthread_exit when it takes the GIL back during finalization, a forced unwind through
/// pybind11's frames, whose handles are then released without the GIL (abort:
/// "PyThreadState_Get: the function must be called with the GIL held", 1 exit in 30 measured
/// 2026-11-28, once in CI), and native work still running while the process's static objects
/// are destroyed crashed it (1 in 60). So the module's atexit hook, which runs before
/// finalization, marks the exit and waits (GIL released) for the work in flight to end; a scope
/// that opens after the mark, or closes during finalization, parks its thread instead of
/// reentering Python. Callers let their own locks go before this destructor runs.
class GilReleased {
 public:
  GilReleased() : state_(PyEval_SaveThread()) {
    ++nativeWork;
    if (exiting) {
      --nativeWork;
      park();
    }
  }
  ~GilReleased() noexcept(false) {
    --nativeWork;
    if (exiting) park();
    PyEval_RestoreThread(state_);
  }
  GilReleased(const GilReleased&) = delete;
  GilReleased& operator=(const GilReleased&) = delete;

 private:
  PyThreadState* state_;
};

/// The atexit hook: no native work starts after it, and the work in flight ends first (at most
/// one render per thread).
void waitForNativeWork() {
  exiting = true;
  py::gil_scoped_release released;
  while (nativeWork > 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

/// A scene document, validated: what load_scene returns and Renderer/render take.
struct PyScene {
  Json doc;
  std::filesystem::path baseDir;
  Scene parsed;  ///< at the document's time (light paths evaluated)
};

PyScene makeScene(Json doc, std::filesystem::path baseDir, const std::string& name) {
  PyScene s{std::move(doc), std::move(baseDir), {}};
  try {
    s.parsed = parseScene(sceneAtTime(s.doc, 0.0), s.baseDir);
  } catch (const ConfigError& e) {
    throw ConfigError(name.empty() ? std::string(e.what()) : name + ": " + e.what());
  }
  return s;
}

/// A Renderer that Python threads may share. Every call takes `lock` after releasing the GIL
/// (so a thread waiting for the lock never holds up the one rendering, which needs no GIL), and
/// gives it back before taking the GIL again: set() or `time =` during render() waits for the
/// render instead of replacing the scene and method under it (which crashed the interpreter).
struct PyRenderer {
  explicit PyRenderer(Renderer r) : renderer(std::move(r)) {}
  Renderer renderer;
  std::mutex lock;
};

/// (H, W, 3), or (H, W, 4) with the alpha (1 − view transmittance) as the 4th channel.
py::array_t<float> imageArray(const Image& img, bool rgba = false) {
  if (!rgba) {
    py::array_t<float> a({img.height(), img.width(), 3});
    std::memcpy(a.mutable_data(), img.pixels().data(), img.pixels().size() * sizeof(Vec3));
    return a;
  }
  if (img.alpha().size() != img.pixels().size())
    throw ConfigError("rgba=True: the image has no alpha channel");
  py::array_t<float> a({img.height(), img.width(), 4});
  float* out = a.mutable_data();
  for (size_t i = 0; i < img.pixels().size(); ++i) {
    for (int c = 0; c < 3; ++c) out[4 * i + c] = img.pixels()[i][c];
    out[4 * i + 3] = img.alpha()[i];
  }
  return a;
}

/// A float (H, W, 3) array, or (H, W, 4) with the alpha when `rgba` is allowed. Integer
/// arrays are refused: 8-bit images are display-referred (sRGB-encoded, 0..255), and comparing
/// or writing them as linear radiance would be silently wrong.
Image arrayImage(const py::array& any, const char* what, bool rgba = false) {
  const char kind = any.dtype().kind();
  const std::string shapes = rgba ? "(H, W, 3) or (H, W, 4)" : "(H, W, 3)";
  if (kind != 'f')
    throw ConfigError(std::string(what) + ": expected a float array (linear radiance) of shape " +
                      shapes + ", got dtype " + py::str(any.dtype()).cast<std::string>() +
                      "; convert an 8-bit image to linear floats first");
  if (any.ndim() == 3)
    checkMemory(what,
                "a float copy of an array of " + std::to_string(any.shape(1)) + "x" +
                    std::to_string(any.shape(0)) + " pixels",
                double(any.size()) * sizeof(float));
  const auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(any);
  std::string shape;
  for (py::ssize_t d = 0; d < any.ndim(); ++d)
    shape += (d ? ", " : "") + std::to_string(any.shape(d));
  if (!a || a.ndim() != 3 || (a.shape(2) != 3 && !(rgba && a.shape(2) == 4)) || a.shape(0) < 1 ||
      a.shape(1) < 1)
    throw ConfigError(std::string(what) + ": expected a float array of shape " + shapes +
                      ", got shape (" + shape + ")");
  // The copy is bounded by SCATTERLAB_MEMORY_LIMIT as every image scatterlab makes (issue 37:
  // 6.2 GB resident under a 512 MiB limit).
  checkMemory(
      what,
      "an image of " + std::to_string(a.shape(1)) + "x" + std::to_string(a.shape(0)) + " pixels",
      double(a.shape(0)) * double(a.shape(1)) * double(sizeof(Vec3) + sizeof(float)));
  Image img(int(a.shape(1)), int(a.shape(0)));
  const float* in = a.data();
  const size_t channels = size_t(a.shape(2)), n = img.pixels().size();
  if (channels == 4) img.alpha().resize(n);
  for (size_t i = 0; i < n; ++i) {
    img.pixels()[i] = Vec3(in[channels * i], in[channels * i + 1], in[channels * i + 2]);
    if (channels == 4) img.alpha()[i] = in[channels * i + 3];
  }
  return img;
}

/// `path` as a file name, or ConfigError: a Python str may hold NUL, which the C library reads
/// as its end (issue 37: write_exr(img, 'new\0.exr') wrote 'new', past the extension check).
const std::string& checkedPath(const std::string& path, const char* what) {
  if (path.find('\0') != std::string::npos) {
    std::string shown = path.substr(0, 200);
    for (char& c : shown)
      if (c == '\0') c = '?';
    throw ConfigError(std::string(what) + ": the path '" + shown +
                      "' holds a NUL character ('?' here); a file name cannot");
  }
  return path;
}

/// An image to write holds only finite values, or ConfigError (issue 37: NaN and inf pixels,
/// float64 1e300 among them, were written silently).
const Image& finiteImage(const Image& img, const char* what) {
  if (const NonFiniteValues bad = countNonFinite(img, /*withAlpha=*/true); bad.any())
    throw ConfigError(std::string(what) + ": the image has " + bad.describe() +
                      " (float32 after conversion); nothing was written");
  return img;
}

/// The extension `path` must have for write_exr / write_png (case-insensitive), else
/// ConfigError: a file named x.png holding EXR bytes misleads every viewer.
void requireExtension(const std::string& path, const std::string& ext, const char* what) {
  std::string e = std::filesystem::path(path).extension().string();
  for (char& c : e) c = char(std::tolower((unsigned char)c));
  if (e != ext) throw ConfigError(std::string(what) + ": '" + path + "' does not end in " + ext);
}

py::array_t<float> densityArray(const DensityGrid& g) {
  const IVec3 d = g.dims();
  py::array_t<float> a({d.z, d.y, d.x});
  std::memcpy(a.mutable_data(), g.data().data(), g.data().size() * sizeof(float));
  return a;
}

py::array_t<float> radianceArray(const RadianceGrid& g) {
  const IVec3 d = g.dims();
  py::array_t<float> a({d.z, d.y, d.x, 3});
  std::memcpy(a.mutable_data(), g.data().data(), g.data().size() * sizeof(Vec3));
  return a;
}

py::tuple boundsTuple(const Box& b) {
  return py::make_tuple(py::make_tuple(b.min.x, b.min.y, b.min.z),
                        py::make_tuple(b.max.x, b.max.y, b.max.z));
}

/// (image, stats) or, with volumes, (image, stats, {"density", "radiance", "bounds"}).
py::tuple resultTuple(const RenderResult& r, bool volumes, const Box& bounds, bool rgba) {
  py::object stats = fromJson(r.stats.toJson());
  if (!volumes) return py::make_tuple(imageArray(r.image, rgba), stats);
  py::dict v;
  v["density"] = r.density ? py::object(densityArray(*r.density)) : py::none();
  v["radiance"] = r.radiance ? py::object(radianceArray(*r.radiance)) : py::none();
  v["bounds"] = boundsTuple(bounds);
  return py::make_tuple(imageArray(r.image, rgba), stats, v);
}

/// The error as `scatterlab compare --json` names it (apps/cmd_compare.cpp); the masked figures
/// with a mask.
py::dict errorDict(const ImageError& e, const LightMask* mask) {
  py::dict d;
  d["rel_l2"] = e.relL2;
  d["rel_l1"] = e.relL1;
  d["psnr_db"] = e.psnr;
  d["max_abs"] = e.maxAbs;
  d["visibly_wrong"] = e.visiblyWrong;
  d["visible_threshold"] = kVisibleThreshold;
  if (mask) {
    d["masked_rel_l2"] = e.maskedRelL2;
    d["mask_radius_px"] = e.maskRadius;
    d["masked_lights"] = e.maskedLights;
    d["masked_pixels"] = mask->maskedPixels();
  }
  return d;
}

constexpr const char* kLoadSceneDoc =
    "Scene from a JSON file path, a volume file (.vdb, .sog: framed automatically, as "
    "`scatterlab render smoke.vdb`) or a dict; overrides: {'camera.width': 64} or ['k=v'] as "
    "--set; base_dir: where a dict's relative file names resolve (default: the working "
    "directory)";

/// load_scene and Scene(...): a scene from a JSON file, a volume file or a dict, with --set
/// style overrides (the one way both take).
PyScene loadScene(const py::object& source, const py::object& overrides, const py::object& baseDir,
                  const char* what, const char* baseWhat) {
  const std::vector<std::string> sets = assignments(overrides);
  if (py::isinstance<py::dict>(source)) {
    Json doc = toJson(source);
    for (const auto& a : sets) applyOverride(doc, a);
    const std::filesystem::path base =
        baseDir.is_none()
            ? std::filesystem::current_path()
            : std::filesystem::path(checkedPath(py::str(baseDir).cast<std::string>(), baseWhat));
    GilReleased unlocked;
    return makeScene(std::move(doc), base, "");
  }
  const std::string path = checkedPath(py::str(source), what);
  GilReleased unlocked;
  Json doc = readSceneDocument(path);
  for (const auto& a : sets) applyOverride(doc, a);
  return makeScene(std::move(doc), std::filesystem::path(path).parent_path(), path);
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "scatterlab: real-time single-scattering participating media (C++ core)";
  // Before finalization: no native work of daemon threads outlives the interpreter (GilReleased).
  py::module_::import("atexit").attr("register")(py::cpp_function(&waitForNativeWork));
  initialize();
  m.attr("__version__") = version();

  // One Python exception per C++ type, same message; all derive from scatterlab.Error.
  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  static py::exception<ConfigError> configError(m, "ConfigError", error.ptr());
  static py::exception<IoError> ioError(m, "IoError", error.ptr());
  static py::exception<LimitError> limitError(m, "LimitError", error.ptr());
  static py::exception<GpuError> gpuError(m, "GpuError", error.ptr());
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ConfigError& e) {
      configError(e.what());
    } catch (const IoError& e) {
      ioError(e.what());
    } catch (const LimitError& e) {
      limitError(e.what());
    } catch (const GpuError& e) {
      gpuError(e.what());
    } catch (const Error& e) {
      error(e.what());
    }
  });

  py::class_<PyScene>(m, "Scene", "A validated scene document: Scene(source) or load_scene")
      .def(py::init([](const py::object& source, const py::object& overrides,
                       const py::object& baseDir) {
             return loadScene(source, overrides, baseDir, "Scene", "Scene: base_dir");
           }),
           py::arg("source"), py::arg("overrides") = py::none(), py::arg("base_dir") = py::none(),
           kLoadSceneDoc)
      .def_property_readonly("width", [](const PyScene& s) { return s.parsed.camera.width; })
      .def_property_readonly("height", [](const PyScene& s) { return s.parsed.camera.height; })
      .def_property_readonly(
          "lights", [](const PyScene& s) { return fromJson(lightsJson(s.parsed.lights)); },
          "The lights as parsed (a list of dicts with the scene format's keys: type, and position, "
          "intensity, direction, outer_deg, inner_deg or irradiance as the type has them; a "
          "keyframed light at the scene's time)")
      .def_property_readonly("bounds",
                             [](const PyScene& s) { return boundsTuple(s.parsed.medium.bounds); })
      .def_property_readonly(
          "document", [](const PyScene& s) { return fromJson(s.doc); },
          "The scene as a dict (a copy)")
      .def("__repr__", [](const PyScene& s) {
        return "<scatterlab.Scene " + std::to_string(s.parsed.camera.width) + "x" +
               std::to_string(s.parsed.camera.height) + ", " +
               std::to_string(s.parsed.lights.size()) + " light(s), density '" +
               s.parsed.medium.density->type() + "'>";
      });

  m.def(
      "load_scene",
      [](const py::object& source, const py::object& overrides, const py::object& baseDir) {
        return loadScene(source, overrides, baseDir, "load_scene", "load_scene: base_dir");
      },
      py::arg("source"), py::arg("overrides") = py::none(), py::arg("base_dir") = py::none(),
      kLoadSceneDoc);

  m.def(
      "render",
      [](const PyScene& s, const std::string& method, const std::string& backend, bool volumes,
         bool rgba, std::optional<long long> samples, std::optional<long long> seed) {
        // samples= and seed= are render.sampler.count and .seed, checked as the scene's keys.
        Json doc = s.doc;
        if (samples || seed) {
          Json& render = doc["render"];
          if (!render.is_object()) render = Json::object();
          Json& sampler = render["sampler"];
          if (!sampler.is_object()) sampler = Json::object();
          if (samples) sampler["count"] = *samples;
          if (seed) sampler["seed"] = *seed;
        }
        RenderResult r;
        {
          GilReleased unlocked;
          Renderer renderer(doc, s.baseDir, method, backend);
          r = renderer.render(nullptr);
        }
        return resultTuple(r, volumes, s.parsed.medium.bounds, rgba);
      },
      py::arg("scene"), py::arg("method") = "", py::arg("backend") = "auto",
      py::arg("volumes") = false, py::arg("rgba") = false, py::arg("samples") = py::none(),
      py::arg("seed") = py::none(),
      "Renders the scene: (image float32 (H,W,3), stats dict), plus a dict of the method's "
      "density and radiance volumes with volumes=True. samples= and seed= set the sampler's "
      "count and seed (render.sampler.count, render.sampler.seed: the jittered sampler's) for "
      "the methods with samples; the other methods report them unused, a bad value is the "
      "scene's error");

  py::class_<PyRenderer>(m, "Renderer",
                         "Re-renders one scene as lights, camera or time change, keeping the "
                         "density volume, fitted model and GL context (docs/python.md). Safe to "
                         "share between threads: calls take a lock, so set() or time= during "
                         "render() waits for that render to finish")
      .def(py::init([](const PyScene& s, const std::string& method, const std::string& backend) {
             GilReleased unlocked;
             return std::make_unique<PyRenderer>(Renderer(s.doc, s.baseDir, method, backend));
           }),
           py::arg("scene"), py::arg("method") = "", py::arg("backend") = "auto")
      .def(
          "set",
          [](PyRenderer& r, const std::string& key, const py::object& value) {
            const std::string a = key + "=" + dumps(value, "Renderer.set('" + key + "')");
            GilReleased unlocked;
            const std::lock_guard<std::mutex> hold(r.lock);
            r.renderer.set(a);
          },
          py::arg("key"), py::arg("value"),
          "Sets a scene key by dotted path (lights.0.position) to a JSON-able value (numbers, "
          "lists, dicts, numpy scalars and arrays)")
      .def(
          "set",
          [](PyRenderer& r, const std::string& assignment) {
            if (assignment.find('=') == std::string::npos)
              throw ConfigError("Renderer.set('" + assignment +
                                "'): expected set(key, value) or set('key=VALUE')");
            GilReleased unlocked;
            const std::lock_guard<std::mutex> hold(r.lock);
            r.renderer.set(assignment);
          },
          py::arg("assignment"), "Sets a scene key from 'key=VALUE', as --set and C++ set()")
      .def(
          "set",
          [](PyRenderer& r, const py::object& changes) {
            const std::vector<std::string> all = assignments(changes);
            GilReleased unlocked;
            const std::lock_guard<std::mutex> hold(r.lock);
            r.renderer.setAll(all);
          },
          py::arg("changes"),
          "Sets several keys at once, a dict {key: value} or a list of 'key=VALUE', parsing the "
          "scene once (C++ setAll: what moving many lights a frame wants); all or nothing")
      .def_property(
          "time",
          [](PyRenderer& r) {
            GilReleased unlocked;
            const std::lock_guard<std::mutex> hold(r.lock);
            return r.renderer.time();
          },
          [](PyRenderer& r, double t) {
            GilReleased unlocked;
            const std::lock_guard<std::mutex> hold(r.lock);
            r.renderer.setTime(t);
          },
          "Animation time: light paths and a medium that moves with time")
      .def(
          "render",
          [](PyRenderer& r, bool volumes, bool rgba) {
            RenderResult res;
            Box bounds;
            {
              GilReleased unlocked;
              const std::lock_guard<std::mutex> hold(r.lock);
              res = r.renderer.render(nullptr);
              bounds = r.renderer.scene().medium.bounds;
            }
            return resultTuple(res, volumes, bounds, rgba);
          },
          py::arg("volumes") = false, py::arg("rgba") = false,
          "(image, stats[, volumes]) as scatterlab.render");

  m.def(
      "density_volume",
      [](const PyScene& s) {
        DensityGrid g;
        {
          GilReleased unlocked;
          g = buildDensityVolume(s.parsed);
        }
        return densityArray(g);
      },
      py::arg("scene"),
      "The scene's density volume, float32 (nz, ny, nx) of cell-centre values over its box");

  m.def(
      "compare",
      [](const py::array& a, const py::array& b, const PyScene* scene,
         std::optional<double> maskRadius) {
        const Image img = arrayImage(a, "compare: image"),
                    ref = arrayImage(b, "compare: reference");
        if (maskRadius && !scene)
          throw ConfigError("compare: mask_radius needs scene= (the lights it masks around)");
        if (maskRadius && !(std::isfinite(*maskRadius) && *maskRadius >= 0))
          throw ConfigError("compare: mask_radius must be a finite number of pixels >= 0, got " +
                            std::to_string(*maskRadius));
        ImageError e;
        std::optional<LightMask> mask;
        {
          GilReleased unlocked;
          if (scene) {
            const Camera& c = scene->parsed.camera;
            if (c.width != img.width() || c.height != img.height())
              throw ConfigError("compare: the images are " + std::to_string(img.width()) + "x" +
                                std::to_string(img.height()) + " but the scene's camera is " +
                                std::to_string(c.width) + "x" + std::to_string(c.height) +
                                "; give the scene the images were rendered with");
            mask = lightMask(scene->parsed,
                             maskRadius ? *maskRadius : defaultMaskRadius(c.width, c.height));
            e = compareImages(img, ref, *mask);
          } else {
            e = compareImages(img, ref);
          }
        }
        return errorDict(e, mask ? &*mask : nullptr);
      },
      py::arg("image"), py::arg("reference"), py::arg("scene") = nullptr,
      py::arg("mask_radius") = py::none(),
      "Error of image against reference (docs/metrics.md), with scatterlab compare --json's keys: "
      "rel_l2, rel_l1, psnr_db, max_abs, visibly_wrong, visible_threshold; with scene= (the "
      "scene the images show) also masked_rel_l2 with the pixels next to each light masked, "
      "mask_radius_px (default 1% of the diagonal, at least 2 px; mask_radius= sets it), "
      "masked_lights, masked_pixels");

  m.def(
      "read_exr",
      [](const std::string& path, bool rgba) {
        return imageArray(readExr(checkedPath(path, "read_exr")), rgba);
      },
      py::arg("path"), py::arg("rgba") = false,
      "R, G, B of an OpenEXR file as float32 (H, W, 3); with rgba=True (H, W, 4) with A");
  m.def(
      "write_exr",
      [](const py::array& img, const std::string& path) {
        requireExtension(checkedPath(path, "write_exr"), ".exr", "write_exr");
        writeExr(finiteImage(arrayImage(img, "write_exr: image", true), "write_exr"), path);
      },
      py::arg("image"), py::arg("path"),
      "Writes a float (H, W, 3) array, or (H, W, 4) with A, as OpenEXR (path: *.exr)");
  m.def(
      "write_png",
      [](const py::array& img, const std::string& path, float exposure,
         const std::string& tonemap) {
        requireExtension(checkedPath(path, "write_png"), ".png", "write_png");
        const ToneCurve curve = parseToneCurve(tonemap, "tonemap");
        Image rgb = arrayImage(img, "write_png: image", true);
        finiteImage(rgb, "write_png");
        rgb.alpha().clear();  // the PNG is the RGB (premultiplied: the fog over black)
        writePng(rgb, path, exposure, curve);
      },
      py::arg("image"), py::arg("path"), py::arg("exposure") = 0.0f, py::arg("tonemap") = "aces",
      "Writes an sRGB PNG of a float (H, W, 3) or (H, W, 4) array (path: *.png): 2^exposure, "
      "then the tone curve ('aces' as the tool's default, 'filmic' or 'linear': clamp), then "
      "the sRGB encoding");

  m.def(
      "list_methods",
      []() {
        py::dict out;
        for (const std::string& name : methods().names()) {
          const MethodEntry& e = methods().get(name, "method");
          py::list backends;
          if (e.runsOn(Backend::Cpu)) backends.append("cpu");
          if (e.runsOn(Backend::Gpu)) backends.append("gpu");
          py::dict d;
          d["summary"] = e.summary;
          d["backends"] = backends;
          d["keys"] = e.keys;
          out[py::str(name)] = d;
        }
        return out;
      },
      "The methods of this build: {name: {'summary', 'backends' (of 'cpu', 'gpu'), 'keys' "
      "(the render keys it reads)}}, sorted by name");
}
