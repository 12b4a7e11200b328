#pragma once
/// Write-then-rename: outputs appear complete or not at all.

#include <functional>
#include <string>

namespace scatterlab {

/// Calls write(tmpPath) with a temporary path in the same directory as `path`, then renames it
/// onto `path`. If write throws, or the rename fails, the temporary is removed and the error is
/// rethrown (as IoError for the rename); `path` is untouched.
void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

/// A set of outputs committed together: stage() writes each to a temporary; commit() renames
/// them all; the destructor removes any temporaries not committed.
class PendingOutputs {
 public:
  PendingOutputs() = default;
  PendingOutputs(const PendingOutputs&) = delete;
  PendingOutputs& operator=(const PendingOutputs&) = delete;
  ~PendingOutputs();

  void stage(const std::string& path, const std::function<void(const std::string&)>& write);
  void commit();

 private:
  struct Item {
    std::string tmp, path;
  };
  std::vector<Item> items_;
};

/// Checks that `path` can be created: its directory exists and `path` is not a directory.
/// Throws IoError naming the path.
void checkWritablePath(const std::string& path);

/// Checks that `path` exists and is a regular file. Throws IoError naming it (and `what`).
void checkReadableFile(const std::string& path, const std::string& what = "file");

}  // namespace scatterlab
