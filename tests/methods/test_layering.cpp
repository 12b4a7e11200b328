/// The include graph goes down only (docs/methods.md): api → methods → cpu, gpu, sampling →
/// shading → media, core. A module may include itself and the modules listed for it, nothing else.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>

namespace {

namespace fs = std::filesystem;

TEST(Layering, IncludesGoDownOnly) {
  // gpu/ implements the GPU twin of sampling/'s dynamic sampling and shares its contract; it
  // reads media/ (the .sog model it splats, docs/methods.md: gpu → media, core).
  const std::map<std::string, std::set<std::string>> allowed = {
      {"core", {}},
      {"media", {"core"}},
      {"shading", {"core"}},
      {"sampling", {"core", "shading"}},
      {"cpu", {"core", "media", "shading"}},
      {"gpu", {"core", "media", "shading", "sampling"}},
      {"methods", {"core", "media", "shading", "sampling", "cpu", "gpu"}},
      {"experiment", {"core"}},
      {"api", {"core", "media", "shading", "sampling", "cpu", "gpu", "methods", "experiment"}},
      {"python", {"api", "core"}},
  };
  const std::regex inc("^#include \"([a-z_]+)/");
  int files = 0;
  for (const auto& [module, deps] : allowed) {
    for (const auto& e : fs::directory_iterator(fs::path(SCATTERLAB_SOURCE_DIR) / module)) {
      const std::string ext = e.path().extension().string();
      if (ext != ".h" && ext != ".cpp") continue;
      ++files;
      std::ifstream f(e.path());
      std::string line;
      std::smatch m;
      while (std::getline(f, line))
        if (std::regex_search(line, m, inc) && m[1] != module && !deps.count(m[1]))
          ADD_FAILURE() << e.path().filename() << " (" << module << ") includes " << line;
    }
  }
  EXPECT_GT(files, 50);
}

}  // namespace
