/// Outputs that exist already (issue 26): a failed multi-file commit puts every earlier file
/// back; devices, FIFOs and symbolic links are written through, never replaced; dangling links
/// and loops are named.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "core/atomic_file.h"
#include "core/error.h"
#include "support/cli.h"

namespace fs = std::filesystem;

namespace {

class Outputs : public scatterlab::testing::TempDirTest {
 protected:
  Outputs() : TempDirTest("scatterlab_outputs") {}

  static std::string contents(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
  static std::function<void(std::ostream&)> text(const std::string& t) {
    return [t](std::ostream& os) { os << t; };
  }
  /// Names in the test's directory that look like temporaries or backups (".NAME.tmpPID_N").
  std::vector<std::string> leftovers() const {
    std::vector<std::string> found;
    for (const auto& e : fs::recursive_directory_iterator(dir_))
      if (e.path().filename().string().find(".tmp") != std::string::npos)
        found.push_back(e.path().string());
    return found;
  }
};

template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const scatterlab::IoError& e) {
    return e.what();
  }
  return "(no IoError)";
}

}  // namespace

// The case: `-o dir/mine.exr --png dir/shared.png` where the second rename fails
// removed the user's old mine.exr and reported "Success" (strerror of a stale errno).
TEST_F(Outputs, AFailedCommitLeavesEveryEarlierFileAsItWas) {
  fs::create_directories(dir_ / "sub");
  std::ofstream(dir_ / "mine.exr") << "old mine";
  scatterlab::PendingOutputs out;
  out.stageStream((dir_ / "mine.exr").string(), text("new mine"));
  out.stageStream((dir_ / "new.txt").string(), text("new file"));
  out.stageStream((dir_ / "sub" / "shared.png").string(), text("new shared"));
  // The third output's directory moves away after staging: its rename fails (ENOENT) after
  // the first two succeeded.
  fs::rename(dir_ / "sub", dir_ / "moved");
  const std::string msg = errorOf([&] { out.commit(); });
  EXPECT_NE(msg.find("cannot write '" + (dir_ / "sub" / "shared.png").string() + "'"),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find("No such file or directory"), std::string::npos) << msg;
  EXPECT_EQ(msg.find("Success"), std::string::npos) << msg;
  EXPECT_EQ(contents(dir_ / "mine.exr"), "old mine");  // put back, not removed
  EXPECT_FALSE(fs::exists(dir_ / "new.txt"));          // created by the commit: removed
  fs::remove_all(dir_ / "moved");                      // holds the third temporary
  EXPECT_TRUE(leftovers().empty()) << leftovers().front();
}

TEST_F(Outputs, ATargetThatBecameADirectoryFailsBeforeAnythingIsReplaced) {
  std::ofstream(dir_ / "a.txt") << "old a";
  scatterlab::PendingOutputs out;
  out.stageStream((dir_ / "a.txt").string(), text("new a"));
  out.stageStream((dir_ / "b.txt").string(), text("new b"));
  fs::create_directories(dir_ / "b.txt" / "inside");
  const std::string msg = errorOf([&] { out.commit(); });
  EXPECT_NE(msg.find("cannot write '" + (dir_ / "b.txt").string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("directory"), std::string::npos) << msg;
  EXPECT_EQ(contents(dir_ / "a.txt"), "old a");
  EXPECT_TRUE(fs::is_directory(dir_ / "b.txt" / "inside"));
}

TEST_F(Outputs, ASuccessfulCommitReplacesAndLeavesNoBackups) {
  std::ofstream(dir_ / "a.txt") << "old a";
  scatterlab::PendingOutputs out;
  out.stageStream((dir_ / "a.txt").string(), text("new a"));
  out.stageStream((dir_ / "b.txt").string(), text("new b"));
  out.commit();
  EXPECT_EQ(contents(dir_ / "a.txt"), "new a");
  EXPECT_EQ(contents(dir_ / "b.txt"), "new b");
  EXPECT_TRUE(leftovers().empty()) << leftovers().front();
}

TEST_F(Outputs, ASymbolicLinkToAFileStaysALinkAndTheFileIsReplaced) {
  std::ofstream(dir_ / "real.json") << "old";
  fs::create_symlink(dir_ / "real.json", dir_ / "link.json");
  scatterlab::writeBytesAtomically((dir_ / "link.json").string(), "new");
  EXPECT_TRUE(fs::is_symlink(dir_ / "link.json"));
  EXPECT_EQ(contents(dir_ / "real.json"), "new");
  EXPECT_TRUE(leftovers().empty()) << leftovers().front();
}

TEST_F(Outputs, DevicesAndFifosAreWrittenThroughNeverReplaced) {
  // A link to /dev/null (as root the old code replaced /dev/null itself; through a link in the
  // test's directory it replaced the link with a regular file).
  fs::create_symlink("/dev/null", dir_ / "null");
  scatterlab::writeBytesAtomically((dir_ / "null").string(), "discarded");
  EXPECT_TRUE(fs::is_symlink(dir_ / "null"));
  EXPECT_TRUE(fs::is_character_file("/dev/null"));

  const std::string fifo = (dir_ / "stats.fifo").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string got;
  std::thread reader([&] { got = scatterlab::testing::drainFifo(fifo, std::chrono::seconds(20)); });
  scatterlab::PendingOutputs out;
  out.stageStream(fifo, text("{\"through\": \"the fifo\"}\n"));
  out.stageStream((dir_ / "image.txt").string(), text("image"));
  out.commit();
  reader.join();
  EXPECT_EQ(got, "{\"through\": \"the fifo\"}\n");
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_EQ(contents(dir_ / "image.txt"), "image");
  EXPECT_TRUE(leftovers().empty()) << leftovers().front();
}

TEST_F(Outputs, DanglingLinksAndLoopsAreNamedNotReplaced) {
  fs::create_symlink(dir_ / "nowhere" / "x.exr", dir_ / "dangling.exr");
  std::string msg =
      errorOf([&] { scatterlab::checkWritablePath((dir_ / "dangling.exr").string()); });
  EXPECT_NE(msg.find("is a symbolic link to '" + (dir_ / "nowhere" / "x.exr").string() +
                     "', which does not exist"),
            std::string::npos)
      << msg;
  msg = errorOf([&] { scatterlab::writeBytesAtomically((dir_ / "dangling.exr").string(), "x"); });
  EXPECT_NE(msg.find("which does not exist"), std::string::npos) << msg;
  EXPECT_TRUE(fs::is_symlink(dir_ / "dangling.exr"));
  EXPECT_FALSE(fs::exists(dir_ / "nowhere"));

  fs::create_symlink(dir_ / "loop_b", dir_ / "loop_a");
  fs::create_symlink(dir_ / "loop_a", dir_ / "loop_b");
  msg = errorOf([&] { scatterlab::checkReadableFile((dir_ / "loop_a").string(), "scene"); });
  EXPECT_NE(msg.find("scene '" + (dir_ / "loop_a").string() + "' is a loop of symbolic links"),
            std::string::npos)
      << msg;
  msg = errorOf([&] { scatterlab::checkWritablePath((dir_ / "loop_a").string()); });
  EXPECT_NE(msg.find("is a loop of symbolic links"), std::string::npos) << msg;
  msg = errorOf([&] { scatterlab::checkReadableFile("/dev/zero", "OBJ mesh"); });
  EXPECT_NE(msg.find("OBJ mesh '/dev/zero' is not a regular file"), std::string::npos) << msg;
}
