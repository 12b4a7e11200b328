#include "apps/movie.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <vector>

#include "core/error.h"

extern char** environ;

namespace scatterlab::cli {

namespace {

bool executable(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

}  // namespace

std::string movieFormat(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower((unsigned char)c));
  if (ext == ".mp4") return "mp4";
  if (ext == ".mkv") return "matroska";
  if (ext == ".mov") return "mov";
  if (ext == ".webm") return "webm";
  if (ext == ".gif") return "gif";
  return "";
}

std::string findFfmpeg() {
  if (const char* env = std::getenv("SCATTERLAB_FFMPEG"); env && *env) {
    if (!executable(env))
      throw ConfigError(std::string("--movie: SCATTERLAB_FFMPEG='") + env +
                        "' is not an executable file");
    return env;
  }
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  for (std::string d; std::getline(dirs, d, ':');)
    if (!d.empty() && executable(d + "/ffmpeg")) return d + "/ffmpeg";
  throw ConfigError(
      "--movie needs ffmpeg, and there is none on PATH (Debian: apt-get install ffmpeg; or set "
      "SCATTERLAB_FFMPEG to its path); the frames can be written without --movie");
}

TempDir::TempDir(const std::string& prefix) {
  std::string pattern = (std::filesystem::temp_directory_path() / (prefix + "-XXXXXX")).string();
  if (!::mkdtemp(pattern.data()))
    throw IoError("cannot make a temporary directory '" + pattern + "': " + std::strerror(errno));
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::string movieFramePath(const std::string& dir, int index) {
  char name[32];
  std::snprintf(name, sizeof name, "frame%06d.png", index);
  return (std::filesystem::path(dir) / name).string();
}

void encodeMovie(const std::string& ffmpeg, const std::string& dir, int count, double fps,
                 const std::string& format, const std::string& out) {
  char rate[32];
  std::snprintf(rate, sizeof rate, "%.9g", fps);
  std::vector<std::string> args = {
      ffmpeg,       "-hide_banner",
      "-loglevel",  "error",
      "-nostdin",   "-y",
      "-framerate", rate,
      "-i",         (std::filesystem::path(dir) / "frame%06d.png").string(),
      "-frames:v",  std::to_string(count)};
  if (format == "webm")
    args.insert(args.end(), {"-c:v", "libvpx-vp9", "-pix_fmt", "yuv420p"});
  else if (format != "gif")
    args.insert(args.end(),
                {"-c:v", "libx264", "-pix_fmt", "yuv420p", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"});
  args.insert(args.end(), {"-f", format, out});
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw IoError(std::string("--movie: pipe: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int spawned = ::posix_spawn(&pid, ffmpeg.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  if (spawned != 0) {
    ::close(fds[0]);
    throw IoError("--movie: cannot run '" + ffmpeg + "': " + std::strerror(spawned));
  }
  std::string messages;
  char buf[4096];
  for (ssize_t n; (n = ::read(fds[0], buf, sizeof buf)) != 0;) {
    if (n < 0) {
      if (errno == EINTR) continue;
      break;
    }
    messages.append(buf, std::size_t(n));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  while (!messages.empty() && (messages.back() == '\n' || messages.back() == ' '))
    messages.pop_back();
  if (messages.size() > 800) messages = "…" + messages.substr(messages.size() - 800);
  for (char& c : messages)  // one line of error, as every error of the tool
    if (c == '\n' || c == '\r') c = ' ';
  const std::string how = WIFEXITED(status)
                              ? "exited with status " + std::to_string(WEXITSTATUS(status))
                              : "was killed by signal " + std::to_string(WTERMSIG(status));
  throw IoError("--movie: ffmpeg ('" + ffmpeg + "') " + how + " encoding " + std::to_string(count) +
                " frames" + (messages.empty() ? "" : ": " + messages));
}

}  // namespace scatterlab::cli
