#include "core/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <streambuf>
#include <vector>

#include "core/error.h"

namespace fs = std::filesystem;

namespace scatterlab {
namespace {

/// Temporaries being written, for the signal handler: fixed slots (no allocation, no lock in
/// the handler). A slot is 0 free, 1 being filled, 2 holding a path to unlink on a signal.
constexpr int kTempSlots = 64;
struct TempSlot {
  std::atomic<int> state{0};
  char path[4096];
};
TempSlot g_temps[kTempSlots];

/// Registers `tmp` for removal on SIGINT/SIGTERM/SIGHUP; -1 when every slot is taken or the
/// path is too long (then only a later cleanup of stale temporaries removes it).
int registerTemp(const std::string& tmp) {
  if (tmp.size() >= sizeof(TempSlot::path)) return -1;
  for (int i = 0; i < kTempSlots; ++i) {
    int expected = 0;
    if (g_temps[i].state.compare_exchange_strong(expected, 1)) {
      std::memcpy(g_temps[i].path, tmp.c_str(), tmp.size() + 1);
      g_temps[i].state.store(2);
      return i;
    }
  }
  return -1;
}

void unregisterTemp(int& slot) {
  if (slot >= 0) g_temps[slot].state.store(0);
  slot = -1;
}

extern "C" void removeTempsAndReraise(int sig) {
  for (TempSlot& t : g_temps)
    if (t.state.load() == 2) ::unlink(t.path);
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

/// A new name beside `path` (or in `dir` when given): ".NAME.tmpPID_N".
std::string tempPathFor(const std::string& path, const fs::path& dir = {}) {
  static std::atomic<unsigned> counter{0};
  const fs::path p(path);
  std::string tail(".tmp");
  tail += std::to_string(::getpid());
  tail += "_";
  tail += std::to_string(counter++);
  // A valid output name of up to NAME_MAX (255) bytes must not fail for its temporary's ~15
  // more: the name is shortened to fit (the tail keeps the pattern stale-temporary cleanup
  // looks for).
  std::string stem = p.filename().string();
  if (stem.size() + tail.size() + 1 > 255) stem.resize(255 - tail.size() - 1);
  // Appended piecewise: GCC 12 reports a false -Wrestrict for "." + std::string.
  std::string name(".");
  name += stem;
  name += tail;
  return ((dir.empty() ? p.parent_path() : dir) / name).string();
}

/// errno's text; errno itself may have changed since.
std::string reason(int err) {
  return std::strerror(err);
}

/// A write-only, seekable streambuf over a file descriptor that remembers the first failed
/// write(2)/lseek(2) (std::ofstream forgets: a failed flush in its destructor is silent).
class CheckedFileBuf : public std::streambuf {
 public:
  explicit CheckedFileBuf(int fd) : fd_(fd), buf_(std::size_t(1) << 16) { reset(); }
  /// errno of the first failure, 0 when none.
  int error() const { return err_; }
  bool drain() {
    for (const char* p = pbase(); p < pptr() && err_ == 0;) {
      const ssize_t w = ::write(fd_, p, std::size_t(pptr() - p));
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) {
        err_ = w < 0 ? errno : EIO;
        break;
      }
      p += w;
    }
    reset();
    return err_ == 0;
  }

 protected:
  int_type overflow(int_type ch) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(ch, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(ch);
      pbump(1);
    }
    return traits_type::not_eof(ch);
  }
  int sync() override { return drain() ? 0 : -1; }
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) override {
    if (!drain()) return pos_type(off_type(-1));
    const int whence = dir == std::ios_base::beg   ? SEEK_SET
                       : dir == std::ios_base::cur ? SEEK_CUR
                                                   : SEEK_END;
    const off_t r = ::lseek(fd_, off_t(off), whence);
    if (r < 0) {
      err_ = errno;
      return pos_type(off_type(-1));
    }
    return pos_type(off_type(r));
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
    return seekoff(off_type(pos), std::ios_base::beg, which);
  }

 private:
  void reset() { setp(buf_.data(), buf_.data() + buf_.size()); }
  int fd_;
  int err_ = 0;
  std::vector<char> buf_;
};

/// Writes `write`'s output to `tmp` (created new), checking every step; throws IoError naming
/// `path` (the requested output, never the temporary).
void writeChecked(const std::string& path, const std::string& tmp,
                  const std::function<void(std::ostream&)>& write) {
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) throw IoError("cannot write '" + path + "': " + std::strerror(errno));
  int err = 0;
  try {
    CheckedFileBuf buf(fd);
    std::ostream os(&buf);
    write(os);
    os.flush();
    err = buf.error();
    if (!err && !os) err = EIO;
    if (!err && ::fsync(fd) != 0 && errno != EINVAL && errno != EROFS) err = errno;
  } catch (...) {
    ::close(fd);
    throw;
  }
  if (::close(fd) != 0 && !err) err = errno;
  if (err) throw IoError("cannot write '" + path + "': " + std::strerror(err));
}

/// Rethrows an IoError whose message names the temporary `tmp` with `path` in its place.
[[noreturn]] void rethrowNaming(const std::string& tmp, const std::string& path) {
  try {
    throw;
  } catch (const IoError& e) {
    std::string m = e.what();
    for (std::size_t at; (at = m.find(tmp)) != std::string::npos;) m.replace(at, tmp.size(), path);
    throw IoError(m);
  }
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  PendingOutputs out;
  out.stageStream(path, write);
  out.commit();
}

void writeBytesAtomically(const std::string& path, std::string_view bytes) {
  writeFileAtomically(
      path, [&](std::ostream& os) { os.write(bytes.data(), std::streamsize(bytes.size())); });
}

void removeTemporariesOnSignal() {
  struct sigaction sa {};
  sa.sa_handler = removeTempsAndReraise;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND;
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &sa, nullptr);
}

void checkWritablePath(const std::string& path) {
  if (path.empty()) throw IoError("output path is empty");
  const fs::path p(path);
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode) && ::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    std::error_code ec;
    const fs::path to = fs::read_symlink(p, ec);
    if (err == ELOOP) throw IoError("output '" + path + "' is a loop of symbolic links");
    throw IoError("output '" + path + "' is a symbolic link to '" + to.string() + "', which " +
                  (err == ENOENT ? std::string("does not exist") : reason(err)) +
                  "; give the file it should name, or remove the link");
  }
  std::error_code ec;
  if (fs::is_directory(p, ec)) throw IoError("output '" + path + "' is a directory, not a file");
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    throw IoError("output '" + path + "': directory '" + dir.string() + "' does not exist");
}

void createOutputDirectory(const std::string& dir) {
  std::error_code ec;
  const fs::file_status st = fs::status(dir, ec);
  if (fs::exists(st)) {
    if (!fs::is_directory(st))
      throw IoError("output directory '" + dir + "' exists and is not a directory");
    return;
  }
  fs::create_directories(dir, ec);
  if (ec) throw IoError("cannot create output directory '" + dir + "': " + ec.message());
}

void checkReadableFile(const std::string& path, const std::string& what) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    if (err == ENOENT) throw IoError(what + " '" + path + "' does not exist");
    if (err == ELOOP) throw IoError(what + " '" + path + "' is a loop of symbolic links");
    throw IoError(what + " '" + path + "': " + reason(err));
  }
  if (S_ISDIR(st.st_mode)) throw IoError(what + " '" + path + "' is a directory, not a file");
  if (!S_ISREG(st.st_mode))
    throw IoError(what + " '" + path + "' is not a regular file (a device, FIFO or socket)");
}

void writeAtomically(const std::string& path,
                     const std::function<void(const std::string&)>& write) {
  PendingOutputs out;
  out.stage(path, write);
  out.commit();
}

void PendingOutputs::stage(const std::string& path,
                           const std::function<void(const std::string&)>& write) {
  checkWritablePath(path);
  // Where the bytes go: an existing regular file through a symbolic link is replaced where it
  // is (the link stays a link); an existing device, FIFO or socket (/dev/null, /dev/stdout, a
  // pipe of the shell's >(...)) is written through at commit, never replaced; anything else is
  // created or replaced at `path`.
  Item item{"", path, -1, "", false};
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    item.through = true;
    item.tmp = tempPathFor(path, fs::temp_directory_path());
  } else {
    struct stat lst {};
    if (::lstat(path.c_str(), &lst) == 0 && S_ISLNK(lst.st_mode)) {
      std::error_code ec;
      const fs::path target = fs::canonical(path, ec);
      if (!ec) item.target = target.string();
    }
    item.tmp = tempPathFor(item.destination());
  }
  item.slot = registerTemp(item.tmp);
  try {
    write(item.tmp);
  } catch (const IoError&) {
    std::error_code ec;
    fs::remove(item.tmp, ec);
    unregisterTemp(item.slot);
    rethrowNaming(item.tmp, path);
  } catch (...) {
    std::error_code ec;
    fs::remove(item.tmp, ec);
    unregisterTemp(item.slot);
    throw;
  }
  items_.push_back(item);
}

void PendingOutputs::stageStream(const std::string& path,
                                 const std::function<void(std::ostream&)>& write) {
  stage(path, [&](const std::string& tmp) { writeChecked(path, tmp, write); });
}

namespace {

/// Copies the file `from` into the existing non-regular file `to` (a device, FIFO or socket),
/// opened for writing without creating or replacing it. Returns 0 or the errno of the failure.
int copyInto(const std::string& from, const std::string& to) {
  const int in = ::open(from.c_str(), O_RDONLY | O_CLOEXEC);
  if (in < 0) return errno;
  const int out = ::open(to.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
  if (out < 0) {
    const int err = errno;
    ::close(in);
    return err;
  }
  int err = 0;
  std::vector<char> buf(std::size_t(1) << 16);
  for (;;) {
    const ssize_t n = ::read(in, buf.data(), buf.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) err = errno;
    if (n <= 0) break;
    for (ssize_t done = 0; done < n && !err;) {
      const ssize_t w = ::write(out, buf.data() + done, std::size_t(n - done));
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0)
        err = w < 0 ? errno : EIO;
      else
        done += w;
    }
    if (err) break;
  }
  ::close(in);
  if (::close(out) != 0 && !err && errno != EINVAL) err = errno;
  return err;
}

}  // namespace

void PendingOutputs::commit() {
  // Every target is checked, and every file about to be replaced gets a backup (a hard link,
  // else a copy) before anything is renamed, so that a failure at any point puts back every
  // earlier file as it was: replaced ones from their backups, new ones removed.
  struct Backup {
    std::string path;  ///< empty: the target did not exist
    int slot = -1;
  };
  std::vector<Backup> backups(items_.size());
  const auto dropBackups = [&] {
    for (Backup& b : backups) {
      if (!b.path.empty()) ::unlink(b.path.c_str());
      unregisterTemp(b.slot);
      b.path.clear();
    }
  };
  const auto fail = [&](const Item& item, const std::string& why) {
    dropBackups();
    throw IoError("cannot write '" + item.path + "': " + why);
  };
  for (std::size_t i = 0; i < items_.size(); ++i) {
    const Item& item = items_[i];
    if (item.through) continue;
    const std::string dest = item.destination();
    struct stat st {};
    if (::lstat(dest.c_str(), &st) != 0) {
      if (errno == ENOENT) continue;
      fail(item, reason(errno));
    }
    if (S_ISDIR(st.st_mode)) fail(item, "it is a directory now");
    Backup& b = backups[i];
    b.path = tempPathFor(dest);
    b.slot = registerTemp(b.path);
    if (::link(dest.c_str(), b.path.c_str()) != 0) {
      std::error_code ec;
      fs::copy_file(dest, b.path, ec);
      if (ec) {
        b.path.clear();
        fail(item,
             "cannot keep a copy of the existing file to restore on failure: " + ec.message());
      }
    }
  }
  // Renames first, then the write-throughs, which cannot be undone.
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < items_.size(); ++i)
    if (!items_[i].through) order.push_back(i);
  for (std::size_t i = 0; i < items_.size(); ++i)
    if (items_[i].through) order.push_back(i);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const Item& item = items_[order[k]];
    int err = 0;
    if (item.through) {
      err = copyInto(item.tmp, item.path);
    } else if (::rename(item.tmp.c_str(), item.destination().c_str()) != 0) {
      err = errno;
    }
    if (err == 0) continue;
    // Put back what the renames before this one replaced (rename(2) of the backup is atomic)
    // and remove what they created.
    for (std::size_t j = k; j-- > 0;) {
      const Item& done = items_[order[j]];
      if (done.through) continue;
      const Backup& b = backups[order[j]];
      if (!b.path.empty())
        ::rename(b.path.c_str(), done.destination().c_str());
      else
        ::unlink(done.destination().c_str());
    }
    fail(item, reason(err));
  }
  dropBackups();
  for (Item& item : items_) {
    if (item.through) ::unlink(item.tmp.c_str());
    unregisterTemp(item.slot);
  }
  items_.clear();
}

PendingOutputs::~PendingOutputs() {
  for (Item& item : items_) {
    std::error_code ec;
    fs::remove(item.tmp, ec);
    unregisterTemp(item.slot);
  }
}

}  // namespace scatterlab
