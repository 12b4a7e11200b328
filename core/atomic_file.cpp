#include "core/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <vector>

#include "core/error.h"

namespace fs = std::filesystem;

namespace scatterlab {
namespace {

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

}  // namespace

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
  Item item{tempPathFor(path), path};
  try {
    write(item.tmp);
  } catch (...) {
    std::error_code ec;
    fs::remove(item.tmp, ec);
    throw;
  }
  items_.push_back(item);
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
  }
  items_.clear();
}

PendingOutputs::~PendingOutputs() {
  for (const Item& item : items_) {
    std::error_code ec;
    fs::remove(item.tmp, ec);
  }
}

}  // namespace scatterlab
