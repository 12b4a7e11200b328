#pragma once
/// `scatterlab info` handlers by file extension.

#include <string>
#include <vector>

namespace scatterlab::cli {

struct InfoHandler {
  std::string extension;  ///< lower case, with the dot
  std::string what;
  void (*print)(const std::string& path);  ///< throws scatterlab::Error
};

const std::vector<InfoHandler>& infoHandlers();
const InfoHandler* findInfoHandler(const std::string& ext);

}  // namespace scatterlab::cli
