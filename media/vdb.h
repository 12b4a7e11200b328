#pragma once
/// OpenVDB input and output (DESIGN.md §2: a VDB keeps its own index-to-world transform, which
/// may rotate and scale; resampling into the medium box respects it). OpenVDB headers stay in
/// vdb.cpp so that only one translation unit pays for them.

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/density_model.h"

namespace scatterlab {

/// Calls openvdb::initialize() once (thread-safe). Every function below calls it itself.
void ensureOpenVdbInitialized();

/// The VDB reader program's main (apps/vdb_reader.cpp; argv: PATH MEMORY_LIMIT_BYTES PARENT_PID):
/// reads every grid of PATH and writes them to stdout re-serialised by OpenVDB's writer
/// ("G" + stream) or an error ("E" + message), under an address-space limit of the memory limit
/// (0: none), dying with the parent. VDB files are parsed in this program, never in the process
/// that asked (media/vdb.cpp readInChild): OpenVDB's reader trusts the file.
int vdbReaderMain(int argc, char** argv);

/// What `scatterlab info FILE.vdb` prints about one grid.
struct VdbGridInfo {
  std::string name;
  std::string valueType;  ///< OpenVDB's type name: "float", "vec3s", "int32", ...
  std::string gridClass;  ///< "fog volume", "level set", "staggered", "unknown"
  bool affine = true;     ///< the index-to-world map is linear (affine)
  bool savedAsHalf = false;
  glm::dvec3 voxelSize{0.0};
  IVec3 indexMin{0}, indexMax{0};  ///< active voxel index bounding box (inclusive)
  bool empty = true;               ///< no active values
  Box worldBounds;                 ///< axis-aligned world box of the index box's cells
  std::uint64_t activeVoxels = 0;
  std::uint64_t activeTiles = 0;
  std::uint64_t leafNodes = 0;
  bool hasValueRange = false;  ///< scalar grids: min/max of active values; vector: of |v|
  double valueMin = 0, valueMax = 0;
};

/// Reads every grid of a .vdb file (fully, no delayed loading). Throws IoError naming the file
/// when it is missing, not a VDB, truncated or corrupt.
///
/// Untrusted files: the layout (header, metadata, grid descriptors, offsets) is checked in
/// this process, then OpenVDB parses the file in the reader program scatterlab-vdb-reader
/// (vdbReaderMain; spawned, not forked, so threads of the caller cannot deadlock it; under an
/// address-space limit of the memory limit, core/limits.h), which sends the grids back through a
/// pipe, so a crash or huge allocation inside OpenVDB's reader is an IoError, not the end of the
/// caller (docs/reliability.md). $SCATTERLAB_VDB_READER names the program where a build moved it.
std::vector<VdbGridInfo> inspectVdb(const std::string& path);

/// Density from a float (or double, converted) grid of a .vdb file. Sampling goes through
/// OpenVDB's tools::GridSampler with BoxSampler (trilinear in the grid's own index space), so
/// rotated and scaled transforms, active tiles and half-float storage are honoured. Negative
/// values (filter ringing in some fog volumes) read as 0.
class VdbDensity : public DensityModel {
 public:
  /// Loads grid `gridName` of `path`. Throws IoError (missing / not a VDB / truncated file)
  /// or ConfigError (no grid of that name: the message lists the grids present; a grid that
  /// is not float/double; a level set; a transform that is not affine).
  static std::unique_ptr<VdbDensity> load(const std::string& path, const std::string& gridName);
  ~VdbDensity() override;

  std::string type() const override { return "vdb"; }
  float eval(const Vec3& x) const override;
  /// Samples the grid at every cell centre (parallel over z slices, one accessor per task).
  void build(DensityGrid& grid) const override;
  /// The axis-aligned world box of the active index box (voxel cells, so half a voxel beyond
  /// the outermost voxel centres), transformed corner by corner.
  std::optional<Box> naturalBounds() const override { return bounds_; }
  /// The largest active value (clamped at 0, as eval() is), when the grid has a value range.
  std::optional<float> peak() const override;
  std::string describe() const override;

  /// Dims of a dense grid over naturalBounds() whose cells have the grid's smallest voxel edge
  /// (for an axis-aligned grid its cell centres are the VDB's voxel centres), each axis scaled
  /// down so the total stays within `maxVoxels`.
  IVec3 nativeDims(std::int64_t maxVoxels = kMaxGridVoxels) const;
  const VdbGridInfo& info() const { return info_; }

 private:
  VdbDensity() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Box bounds_;
  VdbGridInfo info_;
  std::string path_;
};

/// Loads grid `gridName` and resamples it into a dense grid over its natural bounds at
/// nativeDims(maxVoxels).
DensityGrid loadVdbAsDense(const std::string& path, const std::string& gridName,
                           std::int64_t maxVoxels = kMaxGridVoxels);

/// What an exported volume says about its medium, as grid metadata (docs/media.md): `sigma_t`
/// and `albedo` (float, written when finite) and `units` (string). Blender and Houdini show
/// them; scatterlab reads nothing but the box back.
struct VolumeMetadata {
  float sigmaT = std::numeric_limits<float>::quiet_NaN();
  float albedo = std::numeric_limits<float>::quiet_NaN();
  std::string units = "world units; density per unit length times sigma_t";
};

/// Grid metadata holding the whole box a volume covers (Vec3d, world space): written by
/// writeVdb, read by VdbDensity::load as the natural bounds, so zero-density margins (inactive
/// voxels, background 0) are not lost when an export is read back.
inline constexpr const char* kVdbBoundsMin = "scatterlab_bounds_min";
inline constexpr const char* kVdbBoundsMax = "scatterlab_bounds_max";

/// Writes `grid` as a FloatGrid (fog volume, background 0, zeros inactive) named `name` whose
/// voxel (i, j, k) is the grid's cell (i, j, k): index-to-world = scale by the cell size, then
/// translate to the centre of cell 0. The grid's whole box and `meta` go into the grid's
/// metadata. Written to a temporary and renamed (no partial file).
void writeVdb(const std::string& path, const DensityGrid& grid, const std::string& name = "density",
              const VolumeMetadata& meta = {});

/// Same for a source-radiance volume: a Vec3SGrid (RGB) named `name`.
void writeVdb(const std::string& path, const RadianceGrid& grid,
              const std::string& name = "radiance", const VolumeMetadata& meta = {});

}  // namespace scatterlab
