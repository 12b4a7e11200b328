#include "shading/view_march.h"

#include <string>

#include "core/params.h"

namespace scatterlab {

namespace {

const std::vector<KeyDoc>& rayMarcherKeys() {
  static const std::vector<KeyDoc> keys = {
      {"half_float_volumes", "bool", "false", "true, false",
       "fast CPU march: store the fused density + radiance volume in IEEE half (8 instead of 16 "
       "bytes per voxel; error in docs/benchmarks.md); methods with a radiance volume",
       "true", nullptr, "cpu"},
      {"march_simd", "string", "auto", "auto, sse2, avx2",
       "fast CPU march's kernel: auto = avx2 where the CPU has AVX2, FMA and F16C, else sse2 "
       "(same images within 1e-6); methods with a radiance volume",
       R"("sse2")", nullptr, "cpu"},
      {"slicing", "string", "ray-steps", "ray-steps, view-planes",
       "GPU marcher's layers: each ray's own steps (= CPU samples) or the paper's view-aligned "
       "slabs (raster pipeline); accepted and reported unused on the CPU and under the compute "
       "pipeline",
       R"("view-planes")", nullptr, "gpu-raster"},
  };
  return keys;
}

void parseRayMarcher(Params& p, const Scene&, PipelineSettings& s) {
  RayMarcherSettings r;
  r.halfFloat = p.boolean("half_float_volumes", false);
  const std::string simd = p.choice("march_simd", {"auto", "sse2", "avx2"}, "auto");
  r.simd = simd == "sse2" ? MarchSimd::Sse2 : simd == "avx2" ? MarchSimd::Avx2 : MarchSimd::Auto;
  r.slicing = p.choice("slicing", {"ray-steps", "view-planes"}, "ray-steps") == "ray-steps"
                  ? Slicing::RaySteps
                  : Slicing::ViewPlanes;
  s.integratorKeys.set(r);
}

}  // namespace

const StageDecl& rayMarcherStage() {
  static const StageDecl d{
      .keys = {{rayMarcherKeys, parseRayMarcher}}, .viewMarch = true, .fusedVolumeOnCpu = true};
  return d;
}

}  // namespace scatterlab
