#include "core/params.h"

#include <algorithm>
#include <cfloat>
#include <climits>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "core/grid.h"
#include "core/suggest.h"

namespace scatterlab {
namespace {

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

const char* typeName(const Json& v) {
  if (v.is_null()) return "null";
  if (v.is_boolean()) return "a boolean";
  if (v.is_number()) return "a number";
  if (v.is_string()) return "a string";
  if (v.is_array()) return "an array";
  return "an object";
}

}  // namespace

bool Interval::contains(double v) const {
  if (std::isnan(v)) return false;
  if (loOpen ? !(v > lo) : !(v >= lo)) return false;
  if (hiOpen ? !(v < hi) : !(v <= hi)) return false;
  return true;
}

std::string Interval::describe() const {
  const bool hasLo = std::isfinite(lo), hasHi = std::isfinite(hi);
  if (hasLo && hasHi)
    return std::string(loOpen ? "(" : "[") + fmt(lo) + ", " + fmt(hi) + (hiOpen ? ")" : "]");
  if (hasLo) return std::string(loOpen ? "> " : ">= ") + fmt(lo);
  if (hasHi) return std::string(hiOpen ? "< " : "<= ") + fmt(hi);
  return "any finite number";
}

std::string describeValue(const Json& v) {
  // Long strings are cut before dump() so a megabyte value is never copied into a message.
  // Invalid UTF-8 (a --set VALUE taken as a string is not checked) is replaced, not thrown
  // (dump's default throws type_error 316: found by fuzz/fuzz_set.cpp).
  const auto dump = [](const Json& j) {
    return j.dump(-1, ' ', false, Json::error_handler_t::replace);
  };
  std::string s = v.is_string() && v.get_ref<const std::string&>().size() > 60
                      ? dump(Json(v.get_ref<const std::string&>().substr(0, 60)))
                      : dump(v);
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

namespace {

/// Thrown from the parser callback; turned into an IoError with the origin by parseJson.
struct JsonRuleBroken {
  std::string why;
};

}  // namespace

Json parseJson(std::string_view text, const std::string& origin) {
  // The callback sees every container start and key in order, so a stack of key sets (one per
  // open object) finds duplicates, and its depth argument bounds the nesting before the parser
  // builds anything deeper.
  std::vector<std::set<std::string>> keys;
  std::vector<bool> isObject;
  const Json::parser_callback_t cb = [&](int depth, Json::parse_event_t ev, Json& parsed) {
    switch (ev) {
      case Json::parse_event_t::object_start:
      case Json::parse_event_t::array_start:
        if (depth >= kMaxJsonDepth)
          throw JsonRuleBroken{"nesting deeper than " + std::to_string(kMaxJsonDepth) +
                               " levels of arrays/objects"};
        isObject.push_back(ev == Json::parse_event_t::object_start);
        if (isObject.back()) keys.emplace_back();
        break;
      case Json::parse_event_t::object_end:
      case Json::parse_event_t::array_end:
        if (!isObject.empty()) {
          if (isObject.back()) keys.pop_back();
          isObject.pop_back();
        }
        break;
      case Json::parse_event_t::key:
        if (!keys.empty() && !keys.back().insert(parsed.get<std::string>()).second)
          throw JsonRuleBroken{"duplicate key " + describeValue(parsed) +
                               " in one object (each key may appear once)"};
        break;
      default:
        break;
    }
    return true;
  };
  try {
    return Json::parse(text.begin(), text.end(), cb, /*allow_exceptions=*/true,
                       /*ignore_comments=*/true);
  } catch (const JsonRuleBroken& e) {
    throw IoError(origin + ": " + e.why);
  } catch (const Json::out_of_range& e) {
    // 406: a number beyond double range; the library reports it without the position.
    std::string what = e.what();
    const auto at = what.find("] ");
    throw IoError(origin + ": " + (at == std::string::npos ? what : what.substr(at + 2)) +
                  " (numbers must be finite and within +-1.8e308)");
  } catch (const Json::exception& e) {
    std::string what = e.what();
    const auto at = what.find("] ");
    throw IoError(origin +
                  ": malformed JSON: " + (at == std::string::npos ? what : what.substr(at + 2)));
  }
}

namespace {

/// Fails unless every component fits a float: narrowing a larger double gives inf.
void checkFloat(const Params& p, const std::string& key, double v, const std::string& what) {
  if (std::abs(v) > double(FLT_MAX))
    p.fail(key,
           what + " " + fmt(v) + " is beyond single precision; allowed: |value| <= 3.40282e+38");
}

}  // namespace

Params::Params(const Json& j, std::string path)
    : Params(std::make_shared<const Json>(j), nullptr, std::move(path)) {}

Params::Params(std::shared_ptr<const Json> root, const Json* j, std::string path)
    : root_(std::move(root)), j_(j ? j : root_.get()), path_(std::move(path)) {
  if (!j_->is_object())
    throw ConfigError((path_.empty() ? std::string("document") : "'" + path_ + "'") +
                      " must be a JSON object, got " + typeName(*j_) + " " + describeValue(*j_));
}

std::string Params::keyPath(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

bool Params::has(const std::string& key) const {
  return j_->contains(key);
}

void Params::fail(const std::string& key, const std::string& why) const {
  throw ConfigError("'" + keyPath(key) + "': " + why);
}

namespace {
std::set<std::string>* activeLog = nullptr;
}  // namespace

Params::ReadLog::ReadLog() {
  if (activeLog) throw std::logic_error("Params::ReadLog: one at a time");
  activeLog = &keys_;
}

Params::ReadLog::~ReadLog() {
  activeLog = nullptr;
}

void Params::mark(const std::string& key) {
  known_.insert(key);
  if (!activeLog) return;
  std::string path = keyPath(key), out;
  // Drop array indices: "lights[3].type" -> "lights[].type".
  for (std::size_t i = 0; i < path.size(); ++i) {
    out += path[i];
    if (path[i] == '[') {
      while (i + 1 < path.size() && path[i + 1] != ']') ++i;
    }
  }
  activeLog->insert(out);
}

void Params::allow(const std::string& key) {
  mark(key);
}

const Json& Params::require(const std::string& key, const char* expected) {
  mark(key);
  auto it = j_->find(key);
  if (it == j_->end())
    fail(key, std::string("required key is missing (expected ") + expected + ")");
  return *it;
}

const Json& Params::raw(const std::string& key) {
  return require(key, "a value");
}

double Params::number(const std::string& key, std::optional<double> def, const Interval& range) {
  mark(key);
  double v;
  if (!has(key)) {
    if (!def) require(key, "a number");
    v = *def;
  } else {
    const Json& j = (*j_)[key];
    if (!j.is_number())
      fail(key, std::string("expected a number, got ") + typeName(j) + " " + describeValue(j));
    v = j.get<double>();
  }
  if (!std::isfinite(v) || !range.contains(v))
    fail(key, "value " + fmt(v) + " is out of range; allowed: " + range.describe());
  return v;
}

float Params::real(const std::string& key, std::optional<double> def, const Interval& range) {
  const double v = number(key, def, range);
  checkFloat(*this, key, v, "value");
  return float(v);
}

long long Params::integer(const std::string& key, std::optional<long long> def,
                          const Interval& range) {
  mark(key);
  long long v;
  if (!has(key)) {
    if (!def) require(key, "an integer");
    v = *def;
  } else {
    const Json& j = (*j_)[key];
    if (j.is_number_unsigned() && j.get<unsigned long long>() > (unsigned long long)LLONG_MAX) {
      fail(key, "value " + std::to_string(j.get<unsigned long long>()) +
                    " is out of range; allowed: " + range.describe());
    } else if (j.is_number_integer() || j.is_number_unsigned()) {
      v = j.get<long long>();
    } else if (j.is_number_float() && std::floor(j.get<double>()) == j.get<double>() &&
               std::abs(j.get<double>()) < 9e15) {
      v = (long long)j.get<double>();
    } else {
      fail(key, std::string("expected an integer, got ") + typeName(j) + " " + describeValue(j));
    }
  }
  if (!range.contains(double(v)))
    fail(key, "value " + std::to_string(v) + " is out of range; allowed: " + range.describe());
  return v;
}

bool Params::boolean(const std::string& key, std::optional<bool> def) {
  mark(key);
  if (!has(key)) {
    if (!def) require(key, "true or false");
    return *def;
  }
  const Json& j = (*j_)[key];
  if (!j.is_boolean())
    fail(key, std::string("expected true or false, got ") + typeName(j) + " " + describeValue(j));
  return j.get<bool>();
}

std::string Params::string(const std::string& key, std::optional<std::string> def) {
  mark(key);
  if (!has(key)) {
    if (!def) require(key, "a string");
    return *def;
  }
  const Json& j = (*j_)[key];
  if (!j.is_string())
    fail(key, std::string("expected a string, got ") + typeName(j) + " " + describeValue(j));
  return j.get<std::string>();
}

std::string Params::choice(const std::string& key, const std::vector<std::string>& allowed,
                           std::optional<std::string> def) {
  const std::string v = string(key, def);
  for (const auto& a : allowed)
    if (a == v) return v;
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + ("'" + a + "'");
  fail(key, "unknown value '" + v + "'" + didYouMean(v, allowed) + "; allowed: " + list);
}

Vec3 Params::vec3(const std::string& key, std::optional<Vec3> def, const Interval& range) {
  mark(key);
  if (!has(key)) {
    if (!def) require(key, "an array of 3 numbers");
    return *def;
  }
  const Json& j = (*j_)[key];
  if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() || !j[2].is_number())
    fail(key, "expected an array of 3 numbers, got " + describeValue(j));
  Vec3 v;
  for (int i = 0; i < 3; ++i) {
    const double x = j[i].get<double>();
    if (!std::isfinite(x) || !range.contains(x))
      fail(key, "component " + std::to_string(i) + " = " + fmt(x) +
                    " is out of range; allowed: " + range.describe());
    checkFloat(*this, key, x, "component " + std::to_string(i) + " =");
    v[i] = float(x);
  }
  return v;
}

Vec3 Params::rgb(const std::string& key, std::optional<Vec3> def, const Interval& range) {
  if (has(key) && (*j_)[key].is_number()) return Vec3(real(key, std::nullopt, range));
  return vec3(key, def, range);
}

IVec3 Params::resolution(const std::string& key, std::optional<IVec3> def,
                         std::size_t bytesPerVoxel, const std::string& what) {
  const Interval range = Interval::closed(1, 4096);
  IVec3 r;
  if (has(key) && (*j_)[key].is_array()) {
    const Vec3 v = vec3(key, std::nullopt, range);
    for (int i = 0; i < 3; ++i) {
      if (v[i] != std::floor(v[i]))
        fail(key, "expected integers, got " + describeValue((*j_)[key]));
      r[i] = int(v[i]);
    }
  } else {
    r = IVec3(int(integer(key, def ? std::optional<long long>(def->x) : std::nullopt, range)));
    if (!has(key) && def) r = *def;
  }
  const long long n = (long long)r.x * r.y * r.z;
  if (n > kMaxGridVoxels)
    fail(key, std::to_string(r.x) + "x" + std::to_string(r.y) + "x" + std::to_string(r.z) + " = " +
                  std::to_string(n) + " voxels is above the memory bound of " +
                  std::to_string(kMaxGridVoxels) + " voxels (512^3)");
  checkMemory(keyPath(key),
              what + " of " + std::to_string(r.x) + "x" + std::to_string(r.y) + "x" +
                  std::to_string(r.z) + " voxels",
              double(n) * double(bytesPerVoxel));
  return r;
}

Params Params::child(const std::string& key) {
  return Params(root_, &require(key, "an object"), keyPath(key));
}

std::vector<Params> Params::children(const std::string& key, bool required) {
  mark(key);
  std::vector<Params> out;
  if (!has(key)) {
    if (required) require(key, "an array of objects");
    return out;
  }
  const Json& j = (*j_)[key];
  if (!j.is_array()) fail(key, std::string("expected an array, got ") + typeName(j));
  for (size_t i = 0; i < j.size(); ++i) {
    const std::string path = keyPath(key) + "[" + std::to_string(i) + "]";
    out.push_back(Params(root_, &j[i], path));
  }
  return out;
}

void Params::finish() const {
  std::string unknown;
  const std::vector<std::string> known(known_.begin(), known_.end());
  for (auto it = j_->begin(); it != j_->end(); ++it)
    if (!known_.count(it.key()))
      unknown +=
          (unknown.empty() ? "'" : ", '") + keyPath(it.key()) + "'" + didYouMean(it.key(), known);
  if (unknown.empty()) return;
  std::string allowed;
  for (const auto& k : known_) allowed += (allowed.empty() ? "" : ", ") + k;
  throw ConfigError("unknown key " + unknown + "; allowed keys" +
                    (path_.empty() ? std::string() : " in '" + path_ + "'") + ": " + allowed);
}

Interval stepRange(float diagonal) {
  return Interval{double(diagonal) * 1e-6, double(diagonal), true, false};
}

void checkOverrideSyntax(const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ConfigError("--set '" + assignment + "': expected key.path=VALUE");
  const std::string path = assignment.substr(0, eq);
  if (std::count(path.begin(), path.end(), '.') >= kMaxJsonDepth)
    throw ConfigError("--set '" + path.substr(0, 60) + "...': key path deeper than " +
                      std::to_string(kMaxJsonDepth) + " levels");
  if (path.front() == '.' || path.back() == '.' || path.find("..") != std::string::npos)
    throw ConfigError("--set '" + assignment + "': empty key in path");
}

bool isOverrideIndex(const std::string& part) {
  return !part.empty() && part.size() <= 9 &&
         part.find_first_not_of("0123456789") == std::string::npos;
}

void applyOverride(Json& doc, const std::string& assignment) {
  checkOverrideSyntax(assignment);
  const auto eq = assignment.find('=');
  const std::string path = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  // JSON where it parses; text that is not JSON at all is a string; JSON that breaks a rule
  // (too deep, duplicate key, 1e400) is an error rather than silently a string.
  const Json value = Json::accept(text, /*ignore_comments=*/true)
                         ? parseJson(text, "--set " + describeValue(Json(assignment)))
                         : Json(text);
  Json* node = &doc;
  std::string walked;
  size_t start = 0;
  while (true) {
    const size_t dot = path.find('.', start);
    const std::string part = path.substr(start, dot == std::string::npos ? dot : dot - start);
    if (part.empty()) throw ConfigError("--set '" + assignment + "': empty key in path");
    const std::string here = walked + (walked.empty() ? "" : ".") + part;
    Json* next = nullptr;
    if (node->is_array()) {
      // lights.0.position: a decimal index into an existing element (arrays never grow here,
      // so a typo cannot create a light with every other key missing).
      if (!isOverrideIndex(part))
        throw ConfigError("--set '" + assignment + "': '" + walked + "' is an array of " +
                          std::to_string(node->size()) + "; '" + part +
                          "' is not an element index (0, 1, ...)");
      const size_t index = std::stoul(part);
      if (index >= node->size())
        throw ConfigError("--set '" + assignment + "': index " + part + " out of range: '" +
                          walked + "' has " + std::to_string(node->size()) + " element" +
                          (node->size() == 1 ? "" : "s"));
      if (dot == std::string::npos) {
        (*node)[index] = value;
        return;
      }
      next = &(*node)[index];
    } else if (node->is_object()) {
      if (dot == std::string::npos) {
        (*node)[part] = value;
        return;
      }
      if (!node->contains(part)) (*node)[part] = Json::object();
      next = &(*node)[part];
    } else {
      throw ConfigError("--set '" + assignment + "': '" + walked +
                        "' is not an object or an array");
    }
    node = next;
    walked = here;
    start = dot + 1;
  }
}

}  // namespace scatterlab
