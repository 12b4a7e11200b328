// Issue 17, binary formats: .sog headers whose sizes lie are refused before anything is
// allocated or read; every single-byte corruption of a .sog or .vdb is an IoError naming the
// file (VDB data is parsed in a child process, so even OpenVDB's own crashes are errors); a
// VDB with one huge constant tile is fitted within the memory and time bounds.

#include <gtest/gtest.h>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "api/scatterlab.h"
#include "media/sog.h"
#include "media/temp_dir.h"
#include "media/vdb.h"
#include "support/cli.h"

namespace scatterlab {
namespace {

std::string slurp(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void spit(const std::string& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), std::streamsize(bytes.size()));
}

/// The .sog checksum (FNV-1a 64 over everything before it), so a test can forge a file whose
/// checksum is right and whose header lies.
void reseal(std::string& s) {
  std::uint64_t h = 14695981039346656037ull;
  for (std::size_t i = 0; i + 8 < s.size(); ++i) {
    h ^= std::uint8_t(s[i]);
    h *= 1099511628211ull;
  }
  std::memcpy(s.data() + s.size() - 8, &h, 8);
}

template <class T>
void poke(std::string& s, std::size_t off, T v) {
  std::memcpy(s.data() + off, &v, sizeof v);
}

SogModel tinyModel() {
  SogModel m;
  m.gaussians = {{Vec3(0.5f), 0.2f, 1.0f}, {Vec3(0.3f, 0.6f, 0.5f), 0.1f, 0.5f}};
  m.residual = ResidualHash(Box{Vec3(0), Vec3(1)}, IVec3(8), 8, 0.01f);
  m.residual.insert(5, 3);
  m.residual.insert(77, -2);
  return m;
}

std::string sogError(const std::string& p) {
  try {
    readSog(p);
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

// Header offsets of the .sog format (docs/media.md): dims at 40, counts at 52 (Gaussians) and
// 56 (residual entries), step at 64; Gaussians from 72, 20 bytes each.
TEST(SogHeader, LyingSizesAreRefusedBeforeAllocating) {
  testing::TempDir tmp("soghdr");
  const std::string p = tmp.file("m.sog");
  writeSog(p, tinyModel());
  const std::string good = slurp(p);
  ASSERT_EQ(good.size(), 72u + 2 * 20 + 2 * 5 + 8);
  // 4e9 Gaussians announced in a 130-byte file: a size mismatch, found from the header alone.
  std::string s = good;
  poke<std::uint32_t>(s, 52, 4000000000u);
  reseal(s);
  spit(p, s);
  std::string m = sogError(p);
  EXPECT_NE(m.find("truncated: 130 bytes, the header announces 80000000090"), std::string::npos)
      << m;
  EXPECT_NE(m.find(p), std::string::npos);
  // More residual entries than lattice cells (8^3 = 512).
  s = good;
  poke<std::uint32_t>(s, 56, 600u);
  reseal(s);
  spit(p, s);
  EXPECT_NE(sogError(p).find("600 residual entries on a lattice of 512 cells"), std::string::npos)
      << sogError(p);
  // A step whose largest code overflows single precision.
  s = good;
  poke<float>(s, 64, 1e36f);
  reseal(s);
  spit(p, s);
  EXPECT_NE(sogError(p).find("invalid residual step"), std::string::npos) << sogError(p);
  // A Gaussian 1e20 away (finite, but |x|^2 overflows float).
  s = good;
  poke<float>(s, 72, 1e20f);
  reseal(s);
  spit(p, s);
  EXPECT_NE(sogError(p).find("1e6 box diagonals"), std::string::npos) << sogError(p);
  // A weight whose sum over the Gaussians overflows.
  s = good;
  poke<float>(s, 72 + 16, 3e38f);
  reseal(s);
  spit(p, s);
  EXPECT_NE(sogError(p).find("overflow single precision"), std::string::npos) << sogError(p);
}

TEST(SogHeader, EveryByteFlippedIsAnIoErrorNamingTheFile) {
  testing::TempDir tmp("sogflip");
  const std::string p = tmp.file("m.sog");
  writeSog(p, tinyModel());
  const std::string good = slurp(p);
  for (std::size_t i = 0; i < good.size(); ++i)
    for (unsigned char bit : {0x01, 0x80}) {
      std::string s = good;
      s[i] = char(s[i] ^ bit);
      spit(p, s);
      const std::string m = sogError(p);
      EXPECT_NE(m.find(p), std::string::npos) << "byte " << i << ": " << m;
    }
}

/// A small exported density (8^3) and its bytes.
std::string smallVdb(const testing::TempDir& tmp) {
  DensityGrid g(Box{Vec3(0), Vec3(1)}, IVec3(8));
  for (std::size_t i = 0; i < g.size(); ++i) g.data()[i] = float(i % 7) * 0.25f;
  const std::string p = tmp.file("small.vdb");
  writeVdb(p, g, "density");
  return p;
}

/// Loads `p` as the density of a scene would; returns "" or the error's message.
std::string vdbError(const std::string& p) {
  try {
    VdbDensity::load(p, "density");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(VdbCorruption, FlippedBytesAreErrorsNamingTheFileNeverACrash) {
  testing::TempDir tmp("vdbflip");
  const std::string good = slurp(smallVdb(tmp));
  ASSERT_GT(good.size(), 400u);
  const std::string p = tmp.file("m.vdb");
  int errors = 0, loaded = 0;
  // 40 positions spread over the file, two bit patterns (each load forks a reader: ~ 30 ms;
  // scripts/fuzz.sh's fuzz_vdb tries millions).
  for (std::size_t i = 0; i < good.size(); i += good.size() / 40)
    for (unsigned char bit : {0x04, 0xff}) {
      std::string s = good;
      s[i] = char(s[i] ^ bit);
      spit(p, s);
      const std::string m = vdbError(p);
      if (m.empty()) {
        ++loaded;  // a flip in a value or an unused byte: a valid (different) file
      } else {
        ++errors;
        EXPECT_NE(m.find(p), std::string::npos) << "byte " << i << ": " << m;
      }
    }
  EXPECT_GT(errors, 10);
  EXPECT_GT(loaded, 0);
}

TEST(VdbCorruption, OpenVdbsBloscHeapOverflowStaysInTheReaderProcess) {
  // fuzz_vdb (10-minute run) reproduced the upstream bug: on this 40 KB mutant of the
  // dragon, OpenVDB's io::bloscFromStream copies past a heap buffer (ASan: heap-buffer-overflow
  // in readCompressedValues). In the reader child of the Release build glibc then aborts on
  // the corrupt heap (signal 6); under ASan the child's report ends it (exit 1). Either way
  // this process gets an IoError naming the file, and lives.
  const std::string p = SCATTERLAB_SOURCE_DIR "/fuzz/regressions/fuzz_vdb_blosc_heap_overflow.vdb";
  const std::string m = vdbError(p);
  EXPECT_EQ(m.rfind("cannot read VDB file '" + p + "': OpenVDB's reader ", 0), 0u) << m;
  EXPECT_NE(m.find("): the file is corrupt (it was read in a separate process)"), std::string::npos)
      << m;
}

// Issue 37: the reader is a program of its own (scatterlab-vdb-reader), found beside the
// executable in the build tree; where it cannot be found the error says so and how to point to it.
TEST(VdbReaderProgram, ReadsBesideTheExecutableAndAMissingOneIsAClearError) {
  testing::TempDir tmp("vdbreader");
  const std::string p = smallVdb(tmp);
  EXPECT_EQ(vdbError(p), "");
  ::setenv("SCATTERLAB_VDB_READER", "/nonexistent/scatterlab-vdb-reader", 1);
  const std::string m = vdbError(p);
  ::unsetenv("SCATTERLAB_VDB_READER");
  EXPECT_EQ(m, "cannot read VDB file '" + p +
                   "': the VDB reader program 'scatterlab-vdb-reader' was not found (tried "
                   "$SCATTERLAB_VDB_READER = '/nonexistent/scatterlab-vdb-reader'); set "
                   "SCATTERLAB_VDB_READER to its path");
  EXPECT_EQ(vdbError(p), "");
}

TEST(VdbCorruption, TruncationsAndLyingLengthsAreCaughtBeforeOpenVdbReads) {
  testing::TempDir tmp("vdbcut");
  const std::string good = slurp(smallVdb(tmp));
  ASSERT_GT(good.size(), 4000u);
  const std::string p = tmp.file("m.vdb");
  // About 40 cuts spread over the file, as the flips above (a load spawns the reader, ~70 ms;
  // a cut every 37 bytes of this 10 KB file, 280 loads, took the test 22 s, 155 s under ASan).
  const std::size_t step = good.size() / 40;
  for (std::size_t keep = 8; keep < good.size(); keep += step) {
    spit(p, good.substr(0, keep));
    const std::string m = vdbError(p);
    EXPECT_NE(m.find(p), std::string::npos) << keep << ": " << m;
  }
  // The grid count (after magic, version, library version, flag, UUID and the metadata count
  // of 0) set to 2^31: refused by the layout check, not attempted by OpenVDB.
  std::string s = good;
  const std::size_t countAt = 8 + 4 + 8 + 1 + 36 + 4;
  ASSERT_EQ(std::uint8_t(s[countAt]), 1u);
  poke<std::uint32_t>(s, countAt, 0x80000000u);
  spit(p, s);
  EXPECT_NE(vdbError(p).find("grids announced in"), std::string::npos) << vdbError(p);
  // The grid name length (just after the count) set to 4 GB.
  s = good;
  poke<std::uint32_t>(s, countAt + 4, 0xfffffff0u);
  spit(p, s);
  EXPECT_NE(vdbError(p).find("grid name of 4294967280 bytes"), std::string::npos) << vdbError(p);
  s = good;
  s[8] = 99;  // file format version 99
  spit(p, s);
  EXPECT_NE(vdbError(p).find("file format version 99"), std::string::npos) << vdbError(p);
}

// An 11 KB-class VDB (here 0.6 KB) holding one active constant tile of 4096^3 voxels: `fit`
// resampled it to 511^3 and took 64 s and 3.8 GB (8.7 min and 4.5 GB at load 8). Now the input
// is resampled to --max-voxels (default 160^3, above every shared input) after a memory check.
TEST(VdbCorruption, OneHugeConstantTileIsFittedWithinTheBounds) {
  testing::TempDir tmp("vdbtile");
  ensureOpenVdbInitialized();
  auto g = openvdb::FloatGrid::create(0.0f);
  g->tree().fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(4095)), 1.0f, true);
  g->setName("density");
  g->setGridClass(openvdb::GRID_FOG_VOLUME);
  const std::string in = tmp.file("tile.vdb");
  openvdb::io::File(in).write({g});
  EXPECT_LT(std::filesystem::file_size(in), 2000u);
  // Over the memory limit: refused before the grid is built, naming the file.
  const auto limited =
      testing::run("fit " + in + " -o " + tmp.file("a.sog") + " --memory-limit 64M");
  EXPECT_EQ(limited.code, 1) << limited.output;
  EXPECT_NE(limited.output.find("'" + in + "': fitting its 159x159x159 grid"), std::string::npos)
      << limited.output;
  EXPECT_FALSE(std::filesystem::exists(tmp.file("a.sog")));
  // With a small --max-voxels: fitted quickly.
  const auto small = testing::run("fit " + in + " -o " + tmp.file("b.sog") +
                                  " --max-voxels 4096 -n 8 --no-image-check");
  EXPECT_EQ(small.code, 0) << small.output;
  EXPECT_NE(small.output.find("input grid       15x15x15"), std::string::npos) << small.output;
}

}  // namespace
}  // namespace scatterlab
