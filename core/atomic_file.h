#pragma once
/// Write-then-rename: outputs appear complete or not at all.

#include <functional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace scatterlab {

/// The one writer of output files. write(os) writes the whole contents to `os`, a seekable
/// ostream over a new temporary file beside `path`; every write, the final flush, fsync and
/// close are checked, and only then is the temporary renamed onto `path`. Any failure (full
/// disk, file size limit, I/O error, or write throwing) removes the temporary, leaves `path`
/// untouched and throws IoError naming `path` and the system's reason.
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// writeFileAtomically with fixed contents.
void writeBytesAtomically(const std::string& path, std::string_view bytes);

/// Calls write(tmpPath) with a temporary path in the same directory as `path`, then renames it
/// onto `path`. If write throws, or the rename fails, the temporary is removed and the error is
/// rethrown (as IoError for the rename); `path` is untouched.
void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

/// A set of outputs committed together: stage() writes each to a temporary; commit() renames
/// them all; the destructor removes any temporaries not committed.
///
/// Outputs that exist already: a regular file is replaced (through a symbolic link, the file
/// it names; the link stays); a device, FIFO or socket (/dev/null, a symbolic link to
/// /proc/self/fd/1, a pipe) is never replaced: its temporary is made in the system's temporary
/// directory and commit() writes the bytes through it (blocking, like a shell's `>`, until a
/// FIFO has a reader). A dangling symbolic link is refused (checkWritablePath).
class PendingOutputs {
 public:
  PendingOutputs() = default;
  PendingOutputs(const PendingOutputs&) = delete;
  PendingOutputs& operator=(const PendingOutputs&) = delete;
  ~PendingOutputs();

  /// Writes through a writer that takes a file name (one that may itself write atomically);
  /// an IoError naming the temporary is rethrown naming `path`.
  void stage(const std::string& path, const std::function<void(const std::string&)>& write);
  /// Writes through the checked stream of writeFileAtomically.
  void stageStream(const std::string& path, const std::function<void(std::ostream&)>& write);
  /// Puts every staged output in place, or none: each file it replaces is first kept as a
  /// backup (a hard link beside it, else a copy), so when a rename or write-through fails,
  /// the outputs already renamed are put back as they were (new ones removed) and the IoError
  /// names the output that failed and the system's reason.
  void commit();

 private:
  struct Item {
    std::string tmp, path;
    int slot;              ///< registration for removal on a signal (-1: none)
    std::string target;    ///< a symbolic link's resolved regular file (empty: `path` itself)
    bool through = false;  ///< an existing non-regular file, written through at commit
    const std::string& destination() const { return target.empty() ? path : target; }
  };
  std::vector<Item> items_;
};

/// Installs handlers for SIGINT, SIGTERM and SIGHUP that unlink every temporary an atomic
/// writer or PendingOutputs holds at that moment (up to 64 at once), then re-raise the signal
/// with its default action (the process still dies by the signal). For programs (the CLI);
/// a library user decides about its own signal handlers.
void removeTemporariesOnSignal();

/// Checks that `path` can be created: its directory exists, `path` is not a directory nor a
/// dangling symbolic link (or a loop of them). Throws IoError naming the path.
void checkWritablePath(const std::string& path);

/// Creates the directory `dir` (and its parents) unless it exists. Throws IoError naming it
/// when it exists as something else (a file) or cannot be created, with the system's reason.
void createOutputDirectory(const std::string& dir);

/// Checks that `path` exists and is a regular file (not a directory, device, FIFO or socket).
/// Throws IoError naming it (and `what`), with the reason: missing, a loop of symbolic links,
/// no permission, ...
void checkReadableFile(const std::string& path, const std::string& what = "file");

}  // namespace scatterlab
