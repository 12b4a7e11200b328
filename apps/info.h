#pragma once
/// `scatterlab info` handlers by file extension.

#include <string>
#include <vector>

#include "core/params.h"

namespace scatterlab::cli {

struct InfoHandler {
  std::string extension;  ///< lower case, with the dot
  std::string what;
  void (*print)(const std::string& path);  ///< throws scatterlab::Error
  /// The same facts as one JSON object (`info --json`), with "file" and "kind".
  Json (*describe)(const std::string& path);
};

const std::vector<InfoHandler>& infoHandlers();
const InfoHandler* findInfoHandler(const std::string& ext);

}  // namespace scatterlab::cli
