#include "media/dense_grid.h"

#include <tbb/parallel_for.h>
#include <algorithm>

#include <filesystem>
#include <fstream>

#include "core/atomic_file.h"
#include "core/error.h"

namespace scatterlab {

void DenseGridDensity::build(DensityGrid& out) const {
  if (out.dims() == grid_.dims() && out.bounds().min == grid_.bounds().min &&
      out.bounds().max == grid_.bounds().max) {
    out.data() = grid_.data();
    return;
  }
  DensityModel::build(out);
}

std::optional<float> DenseGridDensity::peak() const {
  float m = 0.0f;
  for (float v : grid_.data()) m = std::max(m, v);
  return m;
}

std::string DenseGridDensity::describe() const {
  const IVec3 d = grid_.dims();
  return "dense grid " + std::to_string(d.x) + "x" + std::to_string(d.y) + "x" +
         std::to_string(d.z) + " from " + source_;
}

std::vector<float> readRawFloats(const std::string& path, IVec3 dims) {
  checkReadableFile(path, "raw density file");
  const std::uintmax_t expected = std::uintmax_t(dims.x) * dims.y * dims.z * sizeof(float);
  const std::uintmax_t size = std::filesystem::file_size(path);
  if (size != expected)
    throw IoError("raw density file '" + path + "' has " + std::to_string(size) + " bytes; dims " +
                  std::to_string(dims.x) + "x" + std::to_string(dims.y) + "x" +
                  std::to_string(dims.z) + " of float32 need " + std::to_string(expected));
  std::vector<float> v(size_t(dims.x) * dims.y * dims.z);
  std::ifstream in(path, std::ios::binary);
  if (!in.read(reinterpret_cast<char*>(v.data()), std::streamsize(expected)))
    throw IoError("cannot read raw density file '" + path + "'");
  return v;
}

}  // namespace scatterlab
