/// Every key the code reads is documented, and every documented render key is read: the key
/// tables of docs/scene-format.md against what Params records (Params::ReadLog) while every
/// demo scene is loaded and every method and sampler is created on it.

#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "api/scatterlab.h"
#include "core/stages.h"
#include "methods/register.h"
#include "methods/settings.h"

namespace scatterlab {
namespace {

std::string readDoc(const std::string& name) {
  std::ifstream f(std::string(SCATTERLAB_SOURCE_DIR) + "/docs/" + name);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

/// Backticked names in the first column of the key tables between `from` and `to` (or the end),
/// prefixed with the subsection's object ("sampler." under "### `render.sampler`").
std::set<std::string> documentedRenderKeys(const std::string& doc) {
  std::set<std::string> keys;
  std::istringstream in(doc.substr(doc.find("## `render`")));
  std::string line, prefix;
  const std::regex cell("^\\| `([a-z_0-9]+)` \\|");
  std::smatch m;
  while (std::getline(in, line)) {
    if (line.rfind("### Methods", 0) == 0) break;
    if (line.rfind("### `render.sampler`", 0) == 0) prefix = "sampler.";
    if (line.rfind("### `render.shadow_map`", 0) == 0) prefix = "shadow_map.";
    if (std::regex_search(line, m, cell)) keys.insert(prefix + m[1].str());
  }
  return keys;
}

/// Every backticked word of the document, outside fenced code blocks.
std::set<std::string> backticked(const std::string& text) {
  std::string doc;
  bool fenced = false;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("```", 0) == 0) {
      fenced = !fenced;
      continue;
    }
    if (!fenced) doc += line + "\n";
  }
  std::set<std::string> words;
  const std::regex tick("`([^`]+)`");
  for (auto it = std::sregex_iterator(doc.begin(), doc.end(), tick); it != std::sregex_iterator();
       ++it) {
    // "`bounds.min`, ..." and "`phase.type`": each dotted part counts.
    std::string w = (*it)[1].str(), part;
    std::istringstream parts(w);
    while (std::getline(parts, part, '.')) words.insert(part);
    words.insert(w);
  }
  return words;
}

/// The value the key tables give for `row`: its example, or for an object the examples of its
/// own table's keys.
Json example(const KeyDoc& row) {
  if (row.fields) {
    Json o = Json::object();
    for (const KeyDoc& f : row.fields()) o[std::string(f.name)] = example(f);
    return o;
  }
  EXPECT_FALSE(row.example.empty()) << row.name << " has no example value in its table";
  return row.example.empty() ? Json() : Json::parse(row.example);
}

/// The keys read while loading every demo scene and creating every method with each of its
/// keys at its table's example value (so optional ones are read too) and every sampler type on
/// it.
std::set<std::string> keysTheCodeReads() {
  initialize();
  Params::ReadLog log;
  for (const char* name : {"glow", "shaft", "dusty_room", "fig3", "smoke", "cloud", "window",
                           "bunny_spot", "cornell_fog"}) {
    const std::string file = std::string(SCATTERLAB_SOURCE_DIR) + "/data/scenes/" + name + ".json";
    const Scene base = loadScene(file);
    for (const MethodDesc& d : builtinMethods()) {
      Scene s = base;
      s.render = {{"method", d.name}, {"backend", "cpu"}};
      for (const KeyDoc& row : methodKeyTable(d)) s.render[std::string(row.name)] = example(row);
      EXPECT_NO_THROW(createMethod(s)) << name << ", " << d.name << ": " << s.render.dump();
    }
    for (const std::string& type : samplers().names()) {
      if (type == "gaussian-centres" && !base.medium.density->gaussians()) continue;
      Scene s = base;
      s.render = {{"method", "gradient"}, {"sampler", {{"type", type}}}};
      createMethod(s);
    }
  }
  return log.keys();
}

TEST(KeyDocs, EveryRenderKeyReadIsDocumentedAndEveryDocumentedOneIsRead) {
  const std::set<std::string> documented = documentedRenderKeys(readDoc("scene-format.md"));
  ASSERT_GT(documented.size(), 15u) << "the render tables of docs/scene-format.md were not found";
  std::set<std::string> read;
  for (const std::string& k : keysTheCodeReads())
    if (k.rfind("render.", 0) == 0) read.insert(k.substr(7));
  for (const std::string& k : read)
    EXPECT_TRUE(documented.count(k)) << "render." << k << " is read but not documented";
  for (const std::string& k : documented)
    EXPECT_TRUE(read.count(k)) << "render." << k << " is documented but never read";
}

/// The backticked words of the cells of every table row, the last cell (the meaning) aside:
/// the keys tables document, as a row's name or among a type's keys ("| `spot` | `position`,
/// `direction` ... | meaning |"). A mention in prose or in a meaning does not count.
std::set<std::string> tableKeys(const std::string& text) {
  std::string cells;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("| ", 0) != 0) continue;
    const std::size_t last = line.rfind(" | ");
    if (last != std::string::npos && last > 0) cells += line.substr(0, last) + "\n";
  }
  return backticked(cells);
}

TEST(KeyDocs, EverySceneKeyReadIsNamedInTheDocs) {
  // Scene keys outside `render` are documented in scene-format.md's tables and, for the density
  // types from files (OpenVDB, fitted models), in media.md: each key's name must be a row of a
  // table there (a row's name or among a type's keys), not only a word somewhere in the text.
  const std::set<std::string> words = tableKeys(readDoc("scene-format.md") + readDoc("media.md"));
  for (const std::string& path : keysTheCodeReads()) {
    if (path.rfind("render.", 0) == 0) continue;
    std::string leaf = path.substr(path.rfind('.') == std::string::npos ? 0 : path.rfind('.') + 1);
    if (leaf.size() > 2 && leaf.compare(leaf.size() - 2, 2, "[]") == 0)
      leaf.resize(leaf.size() - 2);
    EXPECT_TRUE(words.count(leaf))
        << path << " is read but '" << leaf
        << "' is in no table row of scene-format.md or media.md (outside its meaning)";
  }
}

TEST(KeyDocs, ObjectKeyTableMatchesTheDocs) {
  // The KeyDoc table at the top of core/objects.cpp and the `objects[i]` table of
  // scene-format.md name the same keys (transform's sub-keys are rows of their own there).
  const std::string doc = readDoc("scene-format.md");
  const std::size_t from = doc.find("## `objects[i]`");
  ASSERT_NE(from, std::string::npos);
  std::istringstream in(doc.substr(from, doc.find("\n## ", from + 1) - from));
  std::set<std::string> documented;
  const std::regex cell("^\\| `([a-z_.]+)`(, `([a-z_.]+)`)? \\|");
  std::smatch m;
  for (std::string line; std::getline(in, line);)
    if (std::regex_search(line, m, cell)) {
      documented.insert(m[1].str());
      if (m[3].matched) documented.insert(m[3].str());
    }
  std::set<std::string> table;
  for (const KeyDoc& d : objectKeyDocs()) table.insert(std::string(d.name));
  for (const std::string& k : table) EXPECT_TRUE(documented.count(k)) << k << " not documented";
  for (const std::string& k : documented)
    EXPECT_TRUE(table.count(k) || k.rfind("transform.", 0) == 0) << k << " not in the KeyDoc table";
}

}  // namespace
}  // namespace scatterlab
