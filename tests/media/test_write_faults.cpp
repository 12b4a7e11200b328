// Every output goes through the one checked atomic writer (core/atomic_file.h): a write that
// fails part-way (here: the file size limit, RLIMIT_FSIZE, which fails write(2) with EFBIG as a
// full disk fails it with ENOSPC) throws IoError naming the requested output and leaves neither
// the output nor a temporary behind. Before issue 17, .vdb exports and --stats left truncated
// files with exit 0.

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>
#include <filesystem>
#include <random>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image.h"
#include "media/temp_dir.h"
#include "media/vdb.h"

using namespace scatterlab;
using scatterlab::testing::TempDir;

namespace {

/// Limits the size of files this process writes to `bytes` while alive (SIGXFSZ ignored, so
/// write(2) fails with EFBIG instead of killing the test).
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &old_);
    oldHandler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit r = old_;
    r.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &r);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &old_);
    std::signal(SIGXFSZ, oldHandler_);
  }

 private:
  rlimit old_{};
  void (*oldHandler_)(int) = nullptr;
};

/// Runs `write` under a 16 KiB file size limit; expects an IoError naming `path` (not the
/// temporary) and an empty directory afterwards.
template <class F>
void expectCleanFailure(const TempDir& dir, const std::string& path, F&& write) {
  std::string message;
  {
    FileSizeLimit limit(16 * 1024);
    try {
      write();
    } catch (const IoError& e) {
      message = e.what();
    }
  }
  EXPECT_NE(message.find("'" + path + "'"), std::string::npos) << message;
  EXPECT_EQ(message.find(".tmp"), std::string::npos) << message;
  EXPECT_TRUE(std::filesystem::is_empty(dir.path())) << "left: " << message;
}

/// Noise does not compress: every format must write ~all of its bytes.
std::vector<float> noise(std::size_t n) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> v(n);
  for (float& x : v) x = u(rng);
  return v;
}

/// 128x128 noise: 48 KiB as 8-bit PNG, ~150 KiB as float EXR, both over the 16 KiB limit.
Image noiseImage() {
  Image img(128, 128);
  const auto n = noise(img.pixels().size() * 3);
  for (std::size_t i = 0; i < img.pixels().size(); ++i)
    img.pixels()[i] = Vec3(n[3 * i], n[3 * i + 1], n[3 * i + 2]);
  return img;
}

}  // namespace

TEST(WriteFaults, BytesAndStreamWritersFailCleanly) {
  TempDir dir("faults_bytes");
  const std::string path = dir.file("out.json");
  expectCleanFailure(dir, path, [&] { writeBytesAtomically(path, std::string(100000, 'x')); });
  expectCleanFailure(dir, path, [&] {
    writeFileAtomically(path, [](std::ostream& os) {
      for (int i = 0; i < 100000; ++i) os << 'y';
    });
  });
  // Under the limit the same writer succeeds and leaves exactly the file.
  writeBytesAtomically(path, std::string(1000, 'x'));
  EXPECT_EQ(std::filesystem::file_size(path), 1000u);
}

TEST(WriteFaults, VdbExportFailsCleanlyAndWritesReadableFilesOtherwise) {
  TempDir dir("faults_vdb");
  DensityGrid g(Box{Vec3(0), Vec3(1)}, IVec3(32));
  g.data() = noise(g.size());
  const std::string path = dir.file("d.vdb");
  expectCleanFailure(dir, path, [&] { writeVdb(path, g); });
  writeVdb(path, g);  // streamed layout (io::Stream): io::File must read it back
  const DensityGrid back = loadVdbAsDense(path, "density");
  ASSERT_EQ(back.dims(), g.dims());
  EXPECT_EQ(back.data(), g.data());
}

TEST(WriteFaults, ExrAndPngFailCleanly) {
  TempDir dir("faults_img");
  const Image img = noiseImage();
  const std::string exr = dir.file("o.exr"), png = dir.file("o.png");
  expectCleanFailure(dir, exr, [&] { writeExr(img, exr); });
  expectCleanFailure(dir, png, [&] { writePng(img, png); });
  writeExr(img, exr);
  EXPECT_EQ(readExr(exr).pixels(), img.pixels());
}

TEST(WriteFaults, PendingOutputsNameTheOutputNotTheTemporary) {
  TempDir dir("faults_pending");
  const std::string path = dir.file("o.exr");
  const Image img = noiseImage();
  PendingOutputs out;
  std::string message;
  {
    FileSizeLimit limit(1024);
    try {
      out.stage(path, [&](const std::string& tmp) { writeExr(img, tmp); });
    } catch (const IoError& e) {
      message = e.what();
    }
  }
  EXPECT_NE(message.find("'" + path + "'"), std::string::npos) << message;
  EXPECT_EQ(message.find(".tmp"), std::string::npos) << message;
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}
