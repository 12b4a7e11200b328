#include "media/vdb.h"

#include <malloc.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <algorithm>

#include <dlfcn.h>
#include <fcntl.h>
#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Count.h>
#include <openvdb/tools/Dense.h>
#include <openvdb/tools/Interpolation.h>
#include <poll.h>
#include <spawn.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/limits.h"
#include "core/sanitizers.h"
#include "core/work_limits.h"

// Where the VDB reader program lies (media/CMakeLists.txt; defaults for builds without CMake,
// such as scripts/fuzz.sh, which names it by $SCATTERLAB_VDB_READER).
#ifndef SCATTERLAB_VDB_READER_NAME
#define SCATTERLAB_VDB_READER_NAME "scatterlab-vdb-reader"
#define SCATTERLAB_VDB_READER_FROM_BIN "../libexec/scatterlab"
#define SCATTERLAB_VDB_READER_FROM_PYTHON "../../../../libexec/scatterlab"
#define SCATTERLAB_VDB_READER_BUILD ""
#define SCATTERLAB_VDB_READER_INSTALLED "/usr/local/libexec/scatterlab/scatterlab-vdb-reader"
#endif

namespace scatterlab {

void ensureOpenVdbInitialized() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

namespace {

using openvdb::CoordBBox;
using openvdb::FloatGrid;
using openvdb::GridBase;
using openvdb::Vec3d;

bool startsWithVdbMagic(const std::string& path) {
  // OpenVDB files start with the 64-bit magic number 0x56444220 ("VDB " little endian).
  std::ifstream in(path, std::ios::binary);
  unsigned char b[8] = {};
  if (!in.read(reinterpret_cast<char*>(b), 8)) return false;
  return b[0] == 0x20 && b[1] == 0x42 && b[2] == 0x44 && b[3] == 0x56;
}

/// Reads what can be checked of a VDB file's layout before OpenVDB parses it
/// (openvdb/io/Archive.cc, GridDescriptor.cc): the header, the file metadata, the grid count
/// and each grid descriptor (names, type, offsets). Every length and offset must lie inside
/// the file; a bit flip in them used to make OpenVDB allocate gigabytes or read past buffers.
/// The grids' own data (topology, compressed buffers) is not checked here: see readInChild.
class VdbLayoutCheck {
 public:
  VdbLayoutCheck(const std::string& path, std::uint64_t size) : path_(path), size_(size) {
    in_.open(path, std::ios::binary);
    if (!in_) throw IoError("cannot read VDB file '" + path + "'");
  }

  void run() {
    skip(8, "magic number");
    const auto version = u32("file format version");
    if (version < openvdb::OPENVDB_FILE_VERSION_ROOTNODE_MAP ||
        version > openvdb::OPENVDB_FILE_VERSION)
      fail("file format version " + std::to_string(version) + " (this build reads " +
           std::to_string(openvdb::OPENVDB_FILE_VERSION_ROOTNODE_MAP) + " to " +
           std::to_string(openvdb::OPENVDB_FILE_VERSION) + ")");
    skip(8, "library version");
    skip(1, "grid offsets flag");
    skip(version >= openvdb::OPENVDB_FILE_VERSION_BOOST_UUID ? 36 : 16, "file UUID");
    const auto metaCount = u32("file metadata count");
    for (std::uint32_t m = 0; m < metaCount; ++m) {
      str("metadata name");
      str("metadata type");
      skip(u32("metadata value size"), "metadata value");
    }
    const auto grids = u32("grid count");
    // A grid takes far more than 16 bytes (descriptor, transform, topology).
    if (std::uint64_t(grids) * 16 > size_ - pos_)
      fail(std::to_string(grids) + " grids announced in " + std::to_string(size_) + " bytes");
    for (std::uint32_t g = 0; g < grids; ++g) {
      const std::string name = str("grid name");
      str("grid type");
      if (version >= openvdb::OPENVDB_FILE_VERSION_GRID_INSTANCING) str("instance parent name");
      const std::uint64_t gridPos = u64("grid offset"), blockPos = u64("data offset"),
                          endPos = u64("grid end offset");
      if (endPos == 0) return;  // a stream without offsets: grids follow in order, unknown size
      if (endPos > size_)
        fail("truncated: grid '" + name.substr(0, 64) + "' ends at byte " + std::to_string(endPos) +
             ", the file has " + std::to_string(size_) + " bytes");
      if (!(gridPos <= blockPos && blockPos <= endPos && gridPos >= pos_))
        fail("grid '" + name.substr(0, 64) + "': offsets " + std::to_string(gridPos) + ", " +
             std::to_string(blockPos) + ", " + std::to_string(endPos) + " out of order");
      seek(endPos);
    }
  }

 private:
  [[noreturn]] void fail(const std::string& why) {
    throw IoError("'" + path_ + "' is not a valid VDB file: " + why);
  }
  void need(std::uint64_t n, const char* what) {
    if (n > size_ - pos_)
      fail(std::string("truncated or corrupt ") + what + " at byte " + std::to_string(pos_) + " (" +
           std::to_string(n) + " bytes announced, " + std::to_string(size_ - pos_) + " left)");
  }
  void read(char* p, std::uint64_t n, const char* what) {
    need(n, what);
    in_.read(p, std::streamsize(n));
    if (!in_) fail(std::string("cannot read ") + what);
    pos_ += n;
  }
  void skip(std::uint64_t n, const char* what) {
    need(n, what);
    seek(pos_ + n);
  }
  void seek(std::uint64_t at) {
    in_.seekg(std::streamoff(at));
    pos_ = at;
  }
  std::uint32_t u32(const char* what) {
    std::uint32_t v;
    read(reinterpret_cast<char*>(&v), 4, what);
    return v;
  }
  std::uint64_t u64(const char* what) {
    std::uint64_t v;
    read(reinterpret_cast<char*>(&v), 8, what);
    return v;
  }
  std::string str(const char* what) {
    const std::uint32_t n = u32(what);
    if (n > (1u << 20)) fail(std::string(what) + " of " + std::to_string(n) + " bytes");
    std::string s(n, '\0');
    read(s.data(), n, what);
    return s;
  }

  std::string path_;
  std::uint64_t size_;
  std::uint64_t pos_ = 0;
  std::ifstream in_;
};

/// Reads every grid in this process (no delayed loading, so a truncated file fails here and
/// not later inside a sampler).
openvdb::GridPtrVecPtr readGridsHere(const std::string& path, std::istream& in) {
  try {
    // io::Stream over an istream that throws on a short read: OpenVDB itself does not check
    // every read, and a truncated file would otherwise load as silently incomplete grids.
    in.exceptions(std::ios::failbit | std::ios::badbit);
    openvdb::io::Stream stream(in, /*delayLoad=*/false);
    openvdb::GridPtrVecPtr grids = stream.getGrids();
    if (!grids) throw IoError("cannot read the grids of VDB file '" + path + "'");
    return grids;
  } catch (const openvdb::Exception& e) {
    throw IoError("cannot read VDB file '" + path + "' (truncated or corrupt?): " + e.what());
  } catch (const std::ios_base::failure& e) {
    throw IoError("cannot read VDB file '" + path + "' (truncated or corrupt?): " + e.what());
  } catch (const std::bad_alloc&) {
    throw IoError("cannot read VDB file '" + path + "': corrupt sizes (allocation failed)");
  }
}

bool writeAll(int fd, const char* p, std::size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= std::size_t(w);
  }
  return true;
}

/// Address-space bytes in use now (/proc/self/statm), 0 when unknown.
std::uint64_t addressSpaceInUse() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t pages = 0;
  statm >> pages;
  return pages * std::uint64_t(::sysconf(_SC_PAGE_SIZE));
}

/// The grids of `path` as the reader process sends them: "G" + the grids re-serialised by
/// OpenVDB's writer, or "E" + an error message.
std::string readerReply(const std::string& path) {
  try {
    std::ifstream in(path, std::ios::binary);
    const openvdb::GridPtrVecPtr grids = readGridsHere(path, in);
    std::ostringstream os(std::ios::binary);
    openvdb::io::Stream stream(os);
    stream.setCompression(openvdb::io::COMPRESS_ACTIVE_MASK);
    stream.write(*grids);
    return "G" + std::move(os).str();
  } catch (const std::bad_alloc&) {
    return "Ecannot read VDB file '" + path + "': corrupt sizes (more memory than the limit of " +
           formatBytes(double(memoryLimit())) + ")";
  } catch (const IoError& e) {
    return std::string("E") + e.what();
  } catch (const std::exception& e) {
    return "Ecannot read VDB file '" + path + "' (corrupt?): " + e.what();
  }
}

/// An executable file at `p`.
bool isExecutable(const std::filesystem::path& p) {
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
}

/// Where the reader executable is: $SCATTERLAB_VDB_READER, else beside the module holding this
/// code or the process's executable, or where an installed prefix keeps it relative to those
/// (bin/ -> libexec/scatterlab/, the Python package -> the same), else the build tree's bin/ and
/// the configured install path. Empty (with what was tried) when none exists.
std::string findVdbReader(std::string* tried) {
  if (const char* env = std::getenv("SCATTERLAB_VDB_READER"); env && *env) {
    *tried = "$SCATTERLAB_VDB_READER = '" + std::string(env) + "'";
    return isExecutable(env) ? std::string(env) : "";
  }
  std::vector<std::filesystem::path> dirs;
  std::error_code ec;
  Dl_info info{};
  if (::dladdr(reinterpret_cast<void*>(&findVdbReader), &info) && info.dli_fname &&
      info.dli_fname[0] == '/')
    dirs.push_back(std::filesystem::canonical(info.dli_fname, ec).parent_path());
  if (const auto exe = std::filesystem::canonical("/proc/self/exe", ec); !ec)
    dirs.push_back(exe.parent_path());
  std::vector<std::filesystem::path> candidates;
  for (const auto& d : dirs) {
    candidates.push_back(d / SCATTERLAB_VDB_READER_NAME);
    candidates.push_back(d / SCATTERLAB_VDB_READER_FROM_BIN / SCATTERLAB_VDB_READER_NAME);
    candidates.push_back(d / SCATTERLAB_VDB_READER_FROM_PYTHON / SCATTERLAB_VDB_READER_NAME);
  }
  candidates.push_back(SCATTERLAB_VDB_READER_BUILD);
  candidates.push_back(SCATTERLAB_VDB_READER_INSTALLED);
  for (const auto& c : candidates) {
    if (c.empty()) continue;
    if (isExecutable(c)) return c.lexically_normal().string();
    *tried += (tried->empty() ? "" : ", ") + c.lexically_normal().string();
  }
  return "";
}

/// OpenVDB's reader trusts the file: a bit flip in a compressed block made it overflow a heap
/// buffer (blosc), others make it allocate gigabytes. So a separate process parses the file,
/// under an address-space limit of the memory limit (core/limits.h; not under ASan, whose
/// shadow memory needs the address space), and sends the grids back re-serialised by OpenVDB's
/// writer through a pipe; this process parses only that. A crash, abort or allocation failure
/// there is an IoError naming the file; this process goes on. The reader is a fresh program
/// (posix_spawn of scatterlab-vdb-reader, apps/vdb_reader.cpp), not a fork: a forked copy of a
/// process whose other threads held TBB's or the allocator's locks deadlocked inside OpenVDB's
/// writer (issue 37: Python with two allocating threads, 5 of 5). It dies with this process
/// (PR_SET_PDEATHSIG), and an answer that does not come in time kills it.
openvdb::GridPtrVecPtr readInChild(const std::string& path, std::uint64_t fileBytes) {
  std::string tried;
  const std::string reader = findVdbReader(&tried);
  if (reader.empty())
    throw IoError("cannot read VDB file '" + path +
                  "': the VDB reader program 'scatterlab-vdb-reader' was not found (tried " +
                  tried + "); set SCATTERLAB_VDB_READER to its path");
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw IoError("cannot read VDB file '" + path + "': pipe: " + std::strerror(errno));
  const std::uint64_t limit = kAddressSanitizer ? 0 : memoryLimit();
  const std::string limitArg = std::to_string(limit), parentArg = std::to_string(::getpid());
  std::vector<char*> argv{const_cast<char*>(reader.c_str()), const_cast<char*>(path.c_str()),
                          const_cast<char*>(limitArg.c_str()), const_cast<char*>(parentArg.c_str()),
                          nullptr};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  std::fflush(nullptr);
  pid_t pid = 0;
  const int spawned = ::posix_spawn(&pid, reader.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  if (spawned != 0) {
    ::close(fds[0]);
    throw IoError("cannot read VDB file '" + path + "': cannot start '" + reader +
                  "': " + std::strerror(spawned));
  }
  // The reader parses the whole file before it answers: 2 minutes plus a second per 5 MB.
  const double timeoutS = 120.0 + double(fileBytes) / 5e6;
  const auto start = std::chrono::steady_clock::now();
  std::string data;
  char buf[1 << 16];
  bool timedOut = false;
  for (;;) {
    const double left =
        timeoutS - std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (left <= 0) {
      timedOut = true;
      break;
    }
    pollfd pfd{fds[0], POLLIN, 0};
    const int ready = ::poll(&pfd, 1, int(std::min(left, 1.0) * 1000.0) + 1);
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) continue;
    const ssize_t r = ::read(fds[0], buf, sizeof buf);
    if (r < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (r <= 0) break;
    data.append(buf, std::size_t(r));
  }
  ::close(fds[0]);
  if (timedOut) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (timedOut)
    throw IoError("cannot read VDB file '" + path + "': the reader process gave no answer in " +
                  formatCount(timeoutS) + " s and was stopped");
  if (WIFSIGNALED(status))
    throw IoError("cannot read VDB file '" + path + "': OpenVDB's reader crashed on it (signal " +
                  std::to_string(WTERMSIG(status)) + ", " + strsignal(WTERMSIG(status)) +
                  "): the file is corrupt (it was read in a separate process)");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || data.empty())
    throw IoError("cannot read VDB file '" + path + "': OpenVDB's reader failed on it (exit " +
                  std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                  "): the file is corrupt (it was read in a separate process)");
  if (data[0] == 'E') throw IoError(data.substr(1));
  std::istringstream in(data.substr(1), std::ios::binary);
  return readGridsHere(path, in);
}

/// Opens and fully reads every grid: layout checked here, data parsed in a child process.
openvdb::GridPtrVecPtr readAllGrids(const std::string& path) {
  ensureOpenVdbInitialized();
  checkReadableFile(path, "VDB file");
  if (!startsWithVdbMagic(path))
    throw IoError("'" + path + "' is not an OpenVDB file (no VDB magic number at its start)");
  std::error_code ec;
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) throw IoError("cannot read VDB file '" + path + "': " + ec.message());
  VdbLayoutCheck(path, size).run();
  return readInChild(path, size);
}

std::string className(openvdb::GridClass c) {
  switch (c) {
    case openvdb::GRID_FOG_VOLUME:
      return "fog volume";
    case openvdb::GRID_LEVEL_SET:
      return "level set";
    case openvdb::GRID_STAGGERED:
      return "staggered";
    default:
      return "unknown";
  }
}

Box worldBoxOf(const openvdb::math::Transform& xf, const CoordBBox& bbox) {
  // Cells of the index box: half a voxel beyond the outermost voxel centres.
  const Vec3d lo = bbox.min().asVec3d() - 0.5, hi = bbox.max().asVec3d() + 0.5;
  Vec3d wmin(std::numeric_limits<double>::max()), wmax(-std::numeric_limits<double>::max());
  for (int c = 0; c < 8; ++c) {
    const Vec3d p((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
    const Vec3d w = xf.indexToWorld(p);
    wmin = openvdb::math::minComponent(wmin, w);
    wmax = openvdb::math::maxComponent(wmax, w);
  }
  return Box{Vec3(float(wmin.x()), float(wmin.y()), float(wmin.z())),
             Vec3(float(wmax.x()), float(wmax.y()), float(wmax.z()))};
}

VdbGridInfo describeGrid(const GridBase& g) {
  VdbGridInfo info;
  info.name = g.getName();
  info.valueType = g.valueType();
  info.gridClass = className(g.getGridClass());
  info.affine = g.transform().isLinear();
  info.savedAsHalf = g.saveFloatAsHalf();
  const Vec3d vs = g.voxelSize();
  info.voxelSize = glm::dvec3(vs.x(), vs.y(), vs.z());
  const CoordBBox bbox = g.evalActiveVoxelBoundingBox();
  info.empty = bbox.empty();
  if (!info.empty) {
    info.indexMin = IVec3(bbox.min().x(), bbox.min().y(), bbox.min().z());
    info.indexMax = IVec3(bbox.max().x(), bbox.max().y(), bbox.max().z());
    info.worldBounds = worldBoxOf(g.transform(), bbox);
  }
  info.activeVoxels = g.activeVoxelCount();
  if (const auto* f = dynamic_cast<const FloatGrid*>(&g)) {
    info.activeTiles = f->tree().activeTileCount();
    info.leafNodes = f->tree().leafCount();
    if (!info.empty) {
      const auto mm = openvdb::tools::minMax(f->tree());
      info.hasValueRange = true;
      info.valueMin = mm.min();
      info.valueMax = mm.max();
    }
  } else if (const auto* d = dynamic_cast<const openvdb::DoubleGrid*>(&g)) {
    info.activeTiles = d->tree().activeTileCount();
    info.leafNodes = d->tree().leafCount();
    if (!info.empty) {
      const auto mm = openvdb::tools::minMax(d->tree());
      info.hasValueRange = true;
      info.valueMin = mm.min();
      info.valueMax = mm.max();
    }
  } else if (const auto* v = dynamic_cast<const openvdb::Vec3SGrid*>(&g)) {
    info.activeTiles = v->tree().activeTileCount();
    info.leafNodes = v->tree().leafCount();
    double lo = std::numeric_limits<double>::max(), hi = -lo;
    for (auto it = v->cbeginValueOn(); it; ++it) {
      const double m = it->length();
      lo = std::min(lo, m);
      hi = std::max(hi, m);
    }
    if (!info.empty) {
      info.hasValueRange = true;
      info.valueMin = lo;
      info.valueMax = hi;
    }
  }
  return info;
}

Vec3d toVdb(const Vec3& v) {
  return Vec3d(v.x, v.y, v.z);
}

}  // namespace

int vdbReaderMain(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr,
                 "scatterlab-vdb-reader: a helper of scatterlab, not a tool: it reads a VDB file "
                 "for the process that started it (usage: PATH MEMORY_LIMIT_BYTES PARENT_PID)\n");
    return 2;
  }
  // Die with the process that asked; if it is gone already, there is no one to answer.
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (std::to_string(::getppid()) != argv[3]) return 4;
  // One thread and one malloc arena: the address-space limit below then bounds the file's data,
  // not thread stacks and per-thread arenas the reading does not need.
  ::mallopt(M_ARENA_MAX, 1);
  tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
  ensureOpenVdbInitialized();
  const std::string path = argv[1];
  const std::uint64_t memory = std::strtoull(argv[2], nullptr, 10);
  if (memory > 0) {
    const std::uint64_t limit = memory + addressSpaceInUse();
    const rlimit rl{rlim_t(limit), rlim_t(limit)};
    ::setrlimit(RLIMIT_AS, &rl);
  }
  const std::string out = readerReply(path);
  const int status = writeAll(STDOUT_FILENO, out.data(), out.size()) ? 0 : 3;
  // An error reply ends the process at once: OpenVDB leaks what it was reading when a corrupt
  // stream throws (RootNode::readTopology's node), and under LeakSanitizer each such reader
  // reported it and started llvm-symbolizer for the report, half of the sanitizer tree's time
  // in VdbCorruption.* (docs/reliability.md, "CI's time"). A good file's reader still returns.
  if (out[0] == 'E') ::_exit(status);
  return status;
}

std::vector<VdbGridInfo> inspectVdb(const std::string& path) {
  const openvdb::GridPtrVecPtr grids = readAllGrids(path);
  std::vector<VdbGridInfo> out;
  for (const auto& g : *grids)
    if (g) out.push_back(describeGrid(*g));
  return out;
}

struct VdbDensity::Impl {
  FloatGrid::Ptr grid;
};

VdbDensity::~VdbDensity() = default;

std::unique_ptr<VdbDensity> VdbDensity::load(const std::string& path, const std::string& gridName) {
  const openvdb::GridPtrVecPtr grids = readAllGrids(path);
  GridBase::Ptr found;
  std::string names;
  for (const auto& g : *grids) {
    if (!g) continue;
    names += (names.empty() ? "'" : ", '") + g->getName() + "' (" + g->valueType() + ")";
    if (g->getName() == gridName && !found) found = g;
  }
  if (!found)
    throw ConfigError("VDB file '" + path + "' has no grid named '" + gridName +
                      "'; grids in the file: " + (names.empty() ? "none" : names));
  FloatGrid::Ptr fg = openvdb::gridPtrCast<FloatGrid>(found);
  if (!fg) {
    if (auto dg = openvdb::gridPtrCast<openvdb::DoubleGrid>(found)) {
      // Convert to float: the working density volume is float anyway.
      fg = FloatGrid::create(0.0f);
      fg->setTransform(dg->transform().copy());
      fg->setName(dg->getName());
      fg->setGridClass(dg->getGridClass());
      auto acc = fg->getAccessor();
      for (auto it = dg->cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue())
          acc.setValue(it.getCoord(), float(*it));
        else
          fg->tree().fill(it.getBoundingBox(), float(*it), true);
      }
    } else {
      throw ConfigError("grid '" + gridName + "' of VDB file '" + path +
                        "' holds values of type '" + found->valueType() +
                        "'; a density grid must be 'float' or 'double'");
    }
  }
  if (fg->getGridClass() == openvdb::GRID_LEVEL_SET)
    throw ConfigError("grid '" + gridName + "' of VDB file '" + path +
                      "' is a level set (signed distance), not a fog-volume density");
  if (!fg->transform().isLinear())
    throw ConfigError("grid '" + gridName + "' of VDB file '" + path + "' has a " +
                      fg->transform().mapType() +
                      " transform, which is not affine; only linear (affine) index-to-world "
                      "transforms are supported");
  std::unique_ptr<VdbDensity> d(new VdbDensity());
  d->impl_ = std::make_unique<Impl>();
  d->impl_->grid = fg;
  d->info_ = describeGrid(*fg);
  d->path_ = path;
  if (d->info_.empty)
    throw ConfigError("grid '" + gridName + "' of VDB file '" + path + "' has no active voxels");
  d->bounds_ = d->info_.worldBounds;
  // A scatterlab export names its whole box (zero margins are inactive, background 0).
  const auto lo = fg->getMetadata<openvdb::Vec3DMetadata>(kVdbBoundsMin);
  const auto hi = fg->getMetadata<openvdb::Vec3DMetadata>(kVdbBoundsMax);
  if (lo && hi) {
    const Box box{Vec3(lo->value().x(), lo->value().y(), lo->value().z()),
                  Vec3(hi->value().x(), hi->value().y(), hi->value().z())};
    if (!box.valid())
      throw ConfigError("grid '" + gridName + "' of VDB file '" + path + "': metadata " +
                        kVdbBoundsMin + " must be below " + kVdbBoundsMax + " in every axis");
    d->bounds_ = box;
  }
  return d;
}

float VdbDensity::eval(const Vec3& x) const {
  // The tree itself is the accessor here: thread-safe, no accessor registration per call.
  const FloatGrid& g = *impl_->grid;
  openvdb::tools::GridSampler<FloatGrid::TreeType, openvdb::tools::BoxSampler> s(g.constTree(),
                                                                                 g.transform());
  return std::max(0.0f, s.wsSample(toVdb(x)));
}

void VdbDensity::build(DensityGrid& grid) const {
  const FloatGrid& g = *impl_->grid;
  const IVec3 n = grid.dims();
  tbb::parallel_for(tbb::blocked_range<int>(0, n.z), [&](const tbb::blocked_range<int>& r) {
    FloatGrid::ConstAccessor acc = g.getConstAccessor();
    openvdb::tools::GridSampler<decltype(acc), openvdb::tools::BoxSampler> s(acc, g.transform());
    for (int k = r.begin(); k < r.end(); ++k)
      for (int j = 0; j < n.y; ++j)
        for (int i = 0; i < n.x; ++i)
          grid.at(i, j, k) = std::max(0.0f, s.wsSample(toVdb(grid.cellCenter(i, j, k))));
  });
}

std::optional<float> VdbDensity::peak() const {
  if (!info_.hasValueRange) return std::nullopt;
  return std::max(0.0f, float(info_.valueMax));
}

std::string VdbDensity::describe() const {
  std::ostringstream os;
  os << "OpenVDB grid '" << info_.name << "' of " << path_ << " (" << info_.activeVoxels
     << " active voxels, index box [" << info_.indexMin.x << "," << info_.indexMin.y << ","
     << info_.indexMin.z << "]..[" << info_.indexMax.x << "," << info_.indexMax.y << ","
     << info_.indexMax.z << "], values " << info_.valueMin << ".." << info_.valueMax << ")";
  return os.str();
}

IVec3 VdbDensity::nativeDims(std::int64_t maxVoxels) const {
  const double v = std::min({info_.voxelSize.x, info_.voxelSize.y, info_.voxelSize.z});
  const Vec3 e = bounds_.extent();
  glm::dvec3 d(e.x / v, e.y / v, e.z / v);
  for (int a = 0; a < 3; ++a)
    d[a] = std::abs(d[a] - std::round(d[a])) < 1e-3 ? std::round(d[a]) : std::ceil(d[a]);
  const double n = d.x * d.y * d.z;
  if (n > double(maxVoxels)) d = glm::floor(d * std::cbrt(double(maxVoxels) / n));
  return glm::max(IVec3(d), IVec3(1));
}

DensityGrid loadVdbAsDense(const std::string& path, const std::string& gridName,
                           std::int64_t maxVoxels) {
  const auto vdb = VdbDensity::load(path, gridName);
  DensityGrid g(*vdb->naturalBounds(), vdb->nativeDims(maxVoxels));
  vdb->build(g);
  return g;
}

namespace {

openvdb::math::Transform::Ptr cellTransform(const Box& bounds, IVec3 dims) {
  const glm::dvec3 cell = (glm::dvec3(bounds.max) - glm::dvec3(bounds.min)) / glm::dvec3(dims);
  openvdb::Mat4d m = openvdb::Mat4d::identity();
  m.setToScale(Vec3d(cell.x, cell.y, cell.z));
  m.setTranslation(
      Vec3d(bounds.min.x + 0.5 * cell.x, bounds.min.y + 0.5 * cell.y, bounds.min.z + 0.5 * cell.z));
  return openvdb::math::Transform::createLinearTransform(m);
}

void writeGrids(const std::string& path, openvdb::GridBase::Ptr grid) {
  checkWritablePath(path);
  // io::Stream into the checked stream (io::File writes through an unchecked std::ofstream: a
  // full disk left a truncated file with exit 0); io::File reads the streamed layout back.
  writeFileAtomically(path, [&](std::ostream& os) {
    try {
      openvdb::GridPtrVec grids{grid};
      openvdb::io::Stream(os).write(grids);
    } catch (const openvdb::Exception& e) {
      throw IoError("cannot write VDB file '" + path + "': " + e.what());
    }
  });
}

}  // namespace

namespace {

/// The box and the medium facts of an exported volume, as grid metadata.
void addMetadata(GridBase& g, const Box& b, const VolumeMetadata& meta) {
  g.insertMeta(kVdbBoundsMin, openvdb::Vec3DMetadata(Vec3d(b.min.x, b.min.y, b.min.z)));
  g.insertMeta(kVdbBoundsMax, openvdb::Vec3DMetadata(Vec3d(b.max.x, b.max.y, b.max.z)));
  if (std::isfinite(meta.sigmaT)) g.insertMeta("sigma_t", openvdb::FloatMetadata(meta.sigmaT));
  if (std::isfinite(meta.albedo)) g.insertMeta("albedo", openvdb::FloatMetadata(meta.albedo));
  if (!meta.units.empty()) g.insertMeta("units", openvdb::StringMetadata(meta.units));
}

}  // namespace

void writeVdb(const std::string& path, const DensityGrid& grid, const std::string& name,
              const VolumeMetadata& meta) {
  ensureOpenVdbInitialized();
  const IVec3 n = grid.dims();
  FloatGrid::Ptr g = FloatGrid::create(0.0f);
  const CoordBBox bbox(openvdb::Coord(0, 0, 0), openvdb::Coord(n.x - 1, n.y - 1, n.z - 1));
  // Dense wraps the grid's memory (x fastest, as ours); copyFromDense only reads it.
  openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(
      bbox, const_cast<float*>(grid.data().data()));
  openvdb::tools::copyFromDense(dense, *g, 0.0f);
  g->setTransform(cellTransform(grid.bounds(), n));
  g->setName(name);
  g->setGridClass(openvdb::GRID_FOG_VOLUME);
  addMetadata(*g, grid.bounds(), meta);
  writeGrids(path, g);
}

void writeVdb(const std::string& path, const RadianceGrid& grid, const std::string& name,
              const VolumeMetadata& meta) {
  ensureOpenVdbInitialized();
  const IVec3 n = grid.dims();
  openvdb::Vec3SGrid::Ptr g = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
  std::vector<openvdb::Vec3s> values(grid.size());
  for (size_t i = 0; i < values.size(); ++i)
    values[i] = openvdb::Vec3s(grid.data()[i].x, grid.data()[i].y, grid.data()[i].z);
  const CoordBBox bbox(openvdb::Coord(0, 0, 0), openvdb::Coord(n.x - 1, n.y - 1, n.z - 1));
  openvdb::tools::Dense<openvdb::Vec3s, openvdb::tools::LayoutXYZ> dense(bbox, values.data());
  openvdb::tools::copyFromDense(dense, *g, openvdb::Vec3s(0.0f));
  g->setTransform(cellTransform(grid.bounds(), n));
  g->setName(name);
  g->setVectorType(openvdb::VEC_INVARIANT);
  addMetadata(*g, grid.bounds(), meta);
  writeGrids(path, g);
}

}  // namespace scatterlab
