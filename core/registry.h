#pragma once
/// Name -> factory registry for pipeline stages. Entries are added by explicit registration
/// functions called from scatterlab::initialize() (no static self-registration, which the
/// linker drops from static libraries).

#include <map>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/suggest.h"

namespace scatterlab {

template <class Factory>
class Registry {
 public:
  explicit Registry(std::string what) : what_(std::move(what)) {}

  /// Adds or replaces an entry.
  void add(const std::string& name, Factory f) { entries_[name] = std::move(f); }
  /// The entry `name`, default-constructed on first use.
  Factory& entry(const std::string& name) { return entries_[name]; }
  bool contains(const std::string& name) const { return entries_.count(name) != 0; }

  /// Throws ConfigError naming `key` (a dotted path for the message), the known names and the
  /// likely one for a misspelling; with nothing registered, says to call initialize().
  const Factory& get(const std::string& name, const std::string& key) const {
    auto it = entries_.find(name);
    if (it == entries_.end()) {
      if (entries_.empty())
        throw ConfigError("'" + key + "': unknown " + what_ + " '" + name + "': no " + what_ +
                          " is registered yet; call scatterlab::initialize() once before "
                          "loading scenes or creating methods");
      std::string list;
      for (const auto& [n, f] : entries_) list += (list.empty() ? "'" : ", '") + n + "'";
      throw ConfigError("'" + key + "': unknown " + what_ + " '" + name + "'" +
                        didYouMean(name, names()) + "; allowed: " + list);
    }
    return it->second;
  }

  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& [n, f] : entries_) out.push_back(n);
    return out;
  }

 private:
  std::string what_;
  std::map<std::string, Factory> entries_;
};

}  // namespace scatterlab
