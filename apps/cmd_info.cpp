#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "api/scatterlab.h"
#include "apps/commands.h"
#include "apps/info.h"
#include "core/atomic_file.h"
#ifdef SCATTERLAB_HAS_GPU
#include "gpu/context.h"
#endif
#include "media/sog.h"
#include "media/vdb.h"

namespace scatterlab::cli {

void printSceneInfo(const std::string& path) {
  const Scene s = loadScene(path);
  const Medium& m = s.medium;
  std::printf("scene %s\n", path.c_str());
  std::printf("  medium: box [%g %g %g]..[%g %g %g], %dx%dx%d voxels, sigma_t %g, albedo %g, %s\n",
              m.bounds.min.x, m.bounds.min.y, m.bounds.min.z, m.bounds.max.x, m.bounds.max.y,
              m.bounds.max.z, m.resolution.x, m.resolution.y, m.resolution.z, m.sigmaT, m.albedo,
              m.phase.type == Phase::Type::Isotropic
                  ? "isotropic phase"
                  : ("Henyey-Greenstein g=" + std::to_string(m.phase.g)).c_str());
  std::printf("  density: %s\n", m.density->describe().c_str());
  for (const Light& l : s.lights) {
    const char* t = l.type == Light::Type::Point  ? "point"
                    : l.type == Light::Type::Spot ? "spot"
                                                  : "directional";
    std::printf("  light: %s, position [%g %g %g], direction [%g %g %g], %s [%g %g %g]\n", t,
                l.position.x, l.position.y, l.position.z, l.direction.x, l.direction.y,
                l.direction.z, l.type == Light::Type::Directional ? "irradiance" : "intensity",
                l.intensity.x, l.intensity.y, l.intensity.z);
  }
  const Camera& c = s.camera;
  std::printf("  camera: [%g %g %g] -> [%g %g %g], fov_y %g deg, %dx%d\n", c.position.x,
              c.position.y, c.position.z, c.lookAt.x, c.lookAt.y, c.lookAt.z, c.fovYDeg, c.width,
              c.height);
  std::printf("  render: %s\n", s.render.dump().c_str());
  auto method = createMethod(s);  // validates the render settings
  (void)method;
}

void printImageInfo(const std::string& path) {
  const Image img = readExr(path);
  // Statistics over finite values; NaN and inf are counted, not folded in (a NaN made the
  // mean "-nan" and hid where it came from).
  Vec3 lo(kInfinity), hi(-kInfinity);
  glm::dvec3 sum(0.0), count(0.0);
  size_t nans = 0, infs = 0;
  for (const Vec3& p : img.pixels())
    for (int c = 0; c < 3; ++c) {
      if (std::isnan(p[c])) {
        ++nans;
      } else if (std::isinf(p[c])) {
        ++infs;
      } else {
        lo[c] = std::min(lo[c], p[c]);
        hi[c] = std::max(hi[c], p[c]);
        sum[c] += p[c];
        count[c] += 1.0;
      }
    }
  sum /= glm::max(count, glm::dvec3(1.0));
  std::printf("image %s: %dx%d RGB float\n", path.c_str(), img.width(), img.height());
  std::printf("  min [%g %g %g]  max [%g %g %g]  mean [%g %g %g]\n", lo.x, lo.y, lo.z, hi.x, hi.y,
              hi.z, sum.x, sum.y, sum.z);
  if (nans + infs > 0)
    std::printf("  non-finite: %zu NaN and %zu inf channel values (left out of min/max/mean)\n",
                nans, infs);
}

/// `info --gpu`: the OpenGL device the GPU backend would use (creates the context).
void printGpuInfo() {
#ifdef SCATTERLAB_HAS_GPU
  const gpu::DeviceInfo& i = gpu::context().info();  // GpuError when there is none
  std::printf("gpu: %s\n  vendor: %s\n  renderer: %s\n  version: %s\n  glsl: %s\n",
              i.hardware ? "hardware" : "software rasteriser (--backend auto uses the CPU)",
              i.vendor.c_str(), i.renderer.c_str(), i.version.c_str(), i.glsl.c_str());
  std::printf("  egl: %s platform, %s\n", i.platform.c_str(), i.eglVendor.c_str());
#else
  throw GpuError("this scatterlab was built without the GPU backend (SCATTERLAB_GPU=OFF)");
#endif
}

void printVdbInfo(const std::string& path) {
  const auto grids = inspectVdb(path);
  std::printf("OpenVDB file %s: %zu grid(s)\n", path.c_str(), grids.size());
  for (const VdbGridInfo& g : grids) {
    std::printf("  grid '%s': %s, %s%s%s\n", g.name.c_str(), g.valueType.c_str(),
                g.gridClass.c_str(), g.savedAsHalf ? ", saved as half float" : "",
                g.affine ? "" : ", NON-AFFINE transform");
    std::printf("    voxel size   [%g %g %g]\n", g.voxelSize.x, g.voxelSize.y, g.voxelSize.z);
    if (g.empty) {
      std::printf("    (no active values)\n");
      continue;
    }
    const IVec3 d = g.indexMax - g.indexMin + 1;
    std::printf("    index box    [%d %d %d]..[%d %d %d] (%dx%dx%d)\n", g.indexMin.x, g.indexMin.y,
                g.indexMin.z, g.indexMax.x, g.indexMax.y, g.indexMax.z, d.x, d.y, d.z);
    std::printf("    world box    [%g %g %g]..[%g %g %g] (voxel cells, axis-aligned)\n",
                g.worldBounds.min.x, g.worldBounds.min.y, g.worldBounds.min.z, g.worldBounds.max.x,
                g.worldBounds.max.y, g.worldBounds.max.z);
    std::printf("    active       %llu voxels (%llu active tiles, %llu leaf nodes)\n",
                (unsigned long long)g.activeVoxels, (unsigned long long)g.activeTiles,
                (unsigned long long)g.leafNodes);
    if (g.hasValueRange)
      std::printf("    values       %g .. %g%s\n", g.valueMin, g.valueMax,
                  g.valueType.rfind("vec", 0) == 0 ? " (length)" : "");
  }
}

void printSogInfo(const std::string& path) {
  const SogModel m = readSog(path);
  const ResidualHash& h = m.residual;
  const IVec3 n = h.dims();
  std::printf("sum-of-Gaussians model %s (format version 1, %zu bytes)\n", path.c_str(),
              m.fileBytes());
  std::printf("  gaussians      %zu\n", m.gaussians.size());
  std::printf("  lattice        [%g %g %g]..[%g %g %g], %dx%dx%d\n", h.bounds().min.x,
              h.bounds().min.y, h.bounds().min.z, h.bounds().max.x, h.bounds().max.y,
              h.bounds().max.z, n.x, n.y, n.z);
  std::printf(
      "  residual hash  %zu entries (%.3f%% of the lattice), %d-bit, step %g, "
      "threshold %g\n",
      h.size(), 100.0 * double(h.size()) / (double(n.x) * n.y * n.z), h.bits(), double(h.step()),
      double(m.threshold));
}

Action addInfo(CLI::App& app) {
  auto file = std::make_shared<std::string>();
  auto gpuFlag = std::make_shared<bool>(false);
  CLI::App* c = app.add_subcommand("info", "Describe a scene (.json), image (.exr) or volume");
  c->add_option("file", *file, "File to describe");
  c->add_flag("--gpu", *gpuFlag,
              "Print the OpenGL vendor, renderer and version of the GPU backend");
  return [file, gpuFlag]() {
    if (*gpuFlag) printGpuInfo();
    if (file->empty()) {
      if (*gpuFlag) return 0;
      throw ConfigError("info: give a FILE to describe, or --gpu");
    }
    checkReadableFile(*file);
    std::string ext = std::filesystem::path(*file).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (const InfoHandler* h = findInfoHandler(ext)) {
      h->print(*file);
      return 0;
    }
    std::string known;
    for (const auto& h : infoHandlers()) known += (known.empty() ? "" : ", ") + h.extension;
    throw IoError("info: don't know how to describe '" + *file + "'; known extensions: " + known);
  };
}

const std::vector<InfoHandler>& infoHandlers() {
  static const std::vector<InfoHandler> h = {
      {".json", "scene", printSceneInfo},
      {".exr", "OpenEXR image", printImageInfo},
      {".vdb", "OpenVDB volume", printVdbInfo},
      {".sog", "sum-of-Gaussians model", printSogInfo},
  };
  return h;
}

const InfoHandler* findInfoHandler(const std::string& ext) {
  for (const auto& h : infoHandlers())
    if (h.extension == ext) return &h;
  return nullptr;
}

}  // namespace scatterlab::cli
