#include "core/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
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

std::string tempPathFor(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  const fs::path p(path);
  // Appended piecewise: GCC 12 reports a false -Wrestrict for "." + std::string.
  std::string name(".");
  name += p.filename().string();
  name += ".tmp";
  name += std::to_string(::getpid());
  name += "_";
  name += std::to_string(counter++);
  return (p.parent_path() / name).string();
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
  std::error_code ec;
  if (fs::is_directory(p, ec)) throw IoError("output '" + path + "' is a directory, not a file");
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    throw IoError("output '" + path + "': directory '" + dir.string() + "' does not exist");
}

void checkReadableFile(const std::string& path, const std::string& what) {
  std::error_code ec;
  const fs::path p(path);
  if (!fs::exists(p, ec)) throw IoError(what + " '" + path + "' does not exist");
  if (fs::is_directory(p, ec)) throw IoError(what + " '" + path + "' is a directory, not a file");
  if (!fs::is_regular_file(p, ec)) throw IoError(what + " '" + path + "' is not a regular file");
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
  Item item{tempPathFor(path), path, -1};
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

void PendingOutputs::commit() {
  for (std::size_t i = 0; i < items_.size(); ++i) {
    std::error_code ec;
    fs::rename(items_[i].tmp, items_[i].path, ec);
    if (ec) {
      // Earlier renames already landed; remove them so no partial set of outputs remains.
      for (std::size_t j = 0; j < i; ++j) fs::remove(items_[j].path, ec);
      throw IoError("cannot write '" + items_[i].path + "': " + ec.message());
    }
    unregisterTemp(items_[i].slot);
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
