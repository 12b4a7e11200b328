#pragma once
/// What the tool's end-to-end tests share: running `scatterlab` (SCATTERLAB_CLI) with its exit
/// code and output, and a fixture owning a fresh directory per test.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

namespace scatterlab::testing {

/// The tool tests' tiny scene: one Gaussian blob in the unit box, a point light above it, 16×12
/// pixels, rendered by `exact` (a scene document, parsed by each test file's fixture).
inline constexpr const char* kTinySceneJson = R"({
  "medium": {"bounds": {"min": [0,0,0], "max": [1,1,1]},
             "density": {"type": "gaussians", "blobs": [{"center": [0.5,0.5,0.5], "radius": 0.25, "weight": 1.0}]},
             "resolution": 16, "sigma_t": 4.0, "albedo": 0.6, "phase": {"type": "isotropic"}},
  "lights": [{"type": "point", "position": [0.5,1.4,0.5], "intensity": [4,4,4]}],
  "camera": {"position": [0.5,0.5,-2], "look_at": [0.5,0.5,0.5], "up": [0,1,0], "fov_y_deg": 40,
             "width": 16, "height": 12},
  "render": {"method": "exact"}})";

struct RunResult {
  int code;
  std::string output;  ///< stdout and stderr together
};

/// Runs `PREFIX scatterlab ARGS` through the shell (`prefix`: shell words before the tool, e.g.
/// "timeout 60 "); code is the exit status (-1 when killed).
inline RunResult run(const std::string& args, const std::string& prefix = "") {
  const std::string cmd = prefix + std::string(SCATTERLAB_CLI) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  while (size_t n = fread(buf.data(), 1, buf.size(), p)) out.append(buf.data(), n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

/// A fresh directory per test under the system's temporary directory, removed afterwards. The
/// pid is in its name: several worktrees on one machine share /tmp and may run these at once.
class TempDirTest : public ::testing::Test {
 protected:
  explicit TempDirTest(std::string prefix) : prefix_(std::move(prefix)) {}
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           (prefix_ + "_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  /// Writes `text` to dir/name; returns the path.
  std::string write(const std::string& name, const std::string& text) const {
    const std::filesystem::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  /// The path of dir/name (not created).
  std::string out(const std::string& name) const { return (dir_ / name).string(); }

  std::filesystem::path dir_;

 private:
  std::string prefix_;
};

/// The whole contents of the file at `path` (empty when it cannot be read).
inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Reads a FIFO without blocking the test forever: opened non-blocking (so the open succeeds
/// before a writer exists), polled until a writer has written and closed, or `timeout`.
inline std::string drainFifo(const std::string& path, std::chrono::seconds timeout) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK);
  if (fd < 0) return "(cannot open)";
  std::string got;
  bool wrote = false;
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    pollfd p{fd, POLLIN, 0};
    ::poll(&p, 1, 100);
    char buf[4096];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) {
      got.append(buf, std::size_t(n));
      wrote = true;
    } else if (n == 0 && wrote) {
      break;  // the writer closed its end after writing
    } else if (n == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));  // no writer yet
    }
  }
  ::close(fd);
  return got;
}

}  // namespace scatterlab::testing
