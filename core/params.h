#pragma once
/// Strict reading of JSON objects (scene files, render settings, experiment configs): every
/// read marks its key used, finish() rejects keys nobody read (pbrt's ReportUnused), and every
/// error names the dotted key path, the value and what is allowed.

#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "core/math.h"

namespace scatterlab {

using Json = nlohmann::json;

/// Allowed numeric range, for messages and checks.
struct Interval {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool loOpen = false, hiOpen = false;

  static Interval atLeast(double v) { return {v, std::numeric_limits<double>::infinity()}; }
  static Interval above(double v) {
    return {v, std::numeric_limits<double>::infinity(), true, false};
  }
  static Interval closed(double a, double b) { return {a, b}; }
  static Interval open(double a, double b) { return {a, b, true, true}; }
  bool contains(double v) const;
  std::string describe() const;
};

/// One row of a settings key table (Mitsuba-plugin style), kept at the top of the code that
/// reads the keys: the reader's reference, the list of keys a method knows (methodKeys()), and
/// what tests/methods/test_key_docs.cpp checks docs/scene-format.md against. A key's name is
/// written here once; the reads use the same literal in the same file.
struct KeyDoc {
  std::string_view name;     ///< key in its object, e.g. "delta1"
  std::string_view type;     ///< "number", "int or [nx,ny,nz]", ...
  std::string_view def;      ///< default, in words
  std::string_view range;    ///< allowed values, in words
  std::string_view meaning;  ///< one line
  /// A valid value other than the default, as JSON text (valid on every demo scene): what the
  /// key-docs test sets to reach the code that reads the key when given. Empty for an object
  /// whose keys have a table of their own (`fields`).
  std::string_view example = {};
  /// For an object-valued key: the table of its keys (the test builds its example from it).
  const std::vector<KeyDoc>& (*fields)() = nullptr;
  /// "cpu" or "gpu" when the key means something on that backend only, "gpu-raster" on the
  /// GPU's raster pipeline only: the others accept it and report it in the stats as unused (a
  /// scene valid on one backend is valid on both; MethodPlan::unusedKeys).
  std::string_view only = {};
};

/// Reads one JSON object. A Params shares ownership of the document it reads (the constructor
/// copies `j` once; children share that copy), so it never points at JSON that is gone.
class Params {
 public:
  /// `path` is the dotted location of `j` in its document ("" for the root); `j` must be an
  /// object, else ConfigError.
  Params(const Json& j, std::string path);

  const std::string& path() const { return path_; }
  std::string keyPath(const std::string& key) const;
  bool has(const std::string& key) const;
  const Json& json() const { return *j_; }

  /// Raw value; marks the key used. Throws when missing.
  const Json& raw(const std::string& key);
  /// Marks a key as known without reading it (for keys handled elsewhere).
  void allow(const std::string& key);

  double number(const std::string& key, std::optional<double> def = std::nullopt,
                const Interval& range = {});
  /// A number that must also fit a float (|v| <= FLT_MAX), so narrowing never gives inf.
  float real(const std::string& key, std::optional<double> def = std::nullopt,
             const Interval& range = {});
  long long integer(const std::string& key, std::optional<long long> def = std::nullopt,
                    const Interval& range = {});
  bool boolean(const std::string& key, std::optional<bool> def = std::nullopt);
  std::string string(const std::string& key, std::optional<std::string> def = std::nullopt);
  /// A string from a fixed set; the message lists the set.
  std::string choice(const std::string& key, const std::vector<std::string>& allowed,
                     std::optional<std::string> def = std::nullopt);
  /// A voxel resolution: an integer n (meaning n³) or [nx, ny, nz] of integers, each in
  /// [1, 4096], at most 512³ voxels in all (the one rule for every resolution key). A volume
  /// of `bytesPerVoxel` per voxel (`what`) must also fit the memory limit (core/limits.h):
  /// LimitError naming the key otherwise.
  IVec3 resolution(const std::string& key, std::optional<IVec3> def = std::nullopt,
                   std::size_t bytesPerVoxel = 4, const std::string& what = "the volume");
  /// Array of 3 numbers, each within `range` and within float range.
  Vec3 vec3(const std::string& key, std::optional<Vec3> def = std::nullopt,
            const Interval& range = {});
  /// Either a number (broadcast to RGB) or an array of 3 numbers.
  Vec3 rgb(const std::string& key, std::optional<Vec3> def = std::nullopt,
           const Interval& range = Interval::atLeast(0));
  /// Nested object.
  Params child(const std::string& key);
  /// Array of objects (possibly empty); missing gives an empty list when `required` is false.
  std::vector<Params> children(const std::string& key, bool required = false);

  /// While one exists, every key any Params reads or allows is recorded as its dotted path with
  /// array indices dropped ("lights[].type"): what tests/methods/test_key_docs.cpp checks the
  /// documentation against. One at a time; not thread-safe (tests only).
  class ReadLog {
   public:
    ReadLog();
    ~ReadLog();
    ReadLog(const ReadLog&) = delete;
    ReadLog& operator=(const ReadLog&) = delete;
    const std::set<std::string>& keys() const { return keys_; }

   private:
    std::set<std::string> keys_;
  };

  /// The keys read or allowed so far, sorted.
  std::vector<std::string> knownKeys() const { return {known_.begin(), known_.end()}; }

  /// Throws ConfigError naming every key present but never read, with the allowed keys.
  void finish() const;

  /// Throws a ConfigError for `key` with the given explanation.
  [[noreturn]] void fail(const std::string& key, const std::string& why) const;

 private:
  /// `j` points into *root (null: the root itself).
  Params(std::shared_ptr<const Json> root, const Json* j, std::string path);
  const Json& require(const std::string& key, const char* expected);
  /// Marks `key` known (and records it in the active ReadLog).
  void mark(const std::string& key);

  std::shared_ptr<const Json> root_;  ///< keeps the document alive
  const Json* j_;                     ///< this object, inside *root_
  std::string path_;
  std::set<std::string> known_;
};

/// The allowed range of a step length (march_step, delta1, delta2) in a medium whose box
/// diagonal is `diagonal`: (diagonal·1e-6, diagonal], so that no ray takes more than ~10^6
/// steps. One definition for every step key.
Interval stepRange(float diagonal);

/// Deepest nesting of arrays and objects a JSON document may have (scene files nest 4 deep;
/// the bound keeps every recursive walk of a document, dump() included, far from the stack).
inline constexpr int kMaxJsonDepth = 64;

/// Parses JSON text strictly: comments allowed; nesting deeper than kMaxJsonDepth, a key
/// repeated in one object, and numbers outside double range (1e400) are errors. Throws
/// IoError whose message starts with `origin` (a file name or "--set 'k=v'") and says where.
Json parseJson(std::string_view text, const std::string& origin);

/// Applies `--set a.b.c=VALUE`: VALUE is parsed as JSON where it parses, else taken as a
/// string; missing objects on the way are created. A part that is a decimal number addresses
/// an element of an existing array (`lights.0.position`); an index past the end, or a part that
/// is not an index on an array, or a key below a value that is neither object nor array, is a
/// ConfigError naming the path.
void applyOverride(Json& doc, const std::string& assignment);

/// Whether an override path's `part` is an element index in applyOverride's sense: decimal
/// digits, at most 9 of them (whether the element exists is the caller's check).
bool isOverrideIndex(const std::string& part);

/// The part of applyOverride's checks that needs no document: KEY=VALUE with a key path of
/// non-empty parts, at most kMaxJsonDepth deep. Throws ConfigError naming the assignment; callers
/// check every override before any work (issue 37: `--set '='` and sweep axes "." or "render."
/// were accepted, and every render then failed).
void checkOverrideSyntax(const std::string& assignment);

/// Short printable form of a JSON value for messages (truncated).
std::string describeValue(const Json& v);

}  // namespace scatterlab
