/// Every key the code reads is documented, and every documented render key is read: the key
/// tables of docs/scene-format.md against what Params records (Params::ReadLog) while every
/// demo scene is loaded and every method and sampler is created on it.

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "api/scatterlab.h"
#include "core/stages.h"
#include "methods/register.h"
#include "methods/settings.h"
#include "sampling/samplers.h"

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

/// A cell as the docs and the code both mean it: backticks, quotes and an escaped '|' are
/// markup, the rest is compared letter for letter.
std::string cellText(std::string_view s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '`' || s[i] == '"') continue;
    if (s[i] == '\\' && i + 1 < s.size() && s[i + 1] == '|') continue;
    out += s[i];
  }
  const std::size_t a = out.find_first_not_of(' '), b = out.find_last_not_of(' ');
  return a == std::string::npos ? "" : out.substr(a, b - a + 1);
}

// docs/scene-format.md's render key rows are checked cell by cell against the key tables the
// code reads them by (KeyDoc, what `scatterlab info --keys` prints): each documented row's
// type, default and allowed values are those of a table row of that key, and each table row is
// documented. Keys two families own under one name (`steps`, `downsample`,
// `light_transmittance`) have a row per family.
TEST(KeyDocs, RenderKeyRowsMatchTheKeyTablesCellByCell) {
  initialize();
  std::map<std::string, std::vector<KeyDoc>> code;
  const auto add = [&](const std::string& prefix, const KeyDoc& row) {
    std::vector<KeyDoc>& rows = code[prefix + std::string(row.name)];
    for (const KeyDoc& r : rows)
      if (r.type == row.type && r.def == row.def && r.range == row.range) return;
    rows.push_back(row);
  };
  for (const MethodDesc& d : builtinMethods())
    for (const KeyDoc& row : methodKeyTable(d)) add("", row);
  for (const KeyDoc& row : samplerKeys()) add("sampler.", row);
  for (const KeyDoc& row : shadowMapKeys()) add("shadow_map.", row);

  const std::string doc = readDoc("scene-format.md");
  std::istringstream in(doc.substr(doc.find("## `render`")));
  std::string line, prefix;
  const std::regex row("^\\| `([a-z_0-9]+)` \\|(.*)$");
  std::smatch m;
  std::set<std::pair<std::string, std::size_t>> matched;  // (key, index of its code row)
  int rows = 0;
  while (std::getline(in, line)) {
    if (line.rfind("### Methods", 0) == 0) break;
    if (line.rfind("### `render.sampler`", 0) == 0) prefix = "sampler.";
    if (line.rfind("### `render.shadow_map`", 0) == 0) prefix = "shadow_map.";
    if (!std::regex_search(line, m, row)) continue;
    const std::string key = prefix + m[1].str();
    // The cells after the key, split at each '|' not escaped as "\\|".
    std::vector<std::string> cells(1);
    const std::string rest = m[2].str();
    for (std::size_t i = 0; i < rest.size(); ++i) {
      if (rest[i] == '|' && (i == 0 || rest[i - 1] != '\\'))
        cells.emplace_back();
      else
        cells.back() += rest[i];
    }
    const auto it = code.find(key);
    if (it == code.end() || cells.size() < 4) continue;  // method, backend: createMethod's
    ++rows;
    bool found = false;
    for (std::size_t i = 0; i < it->second.size() && !found; ++i) {
      const KeyDoc& k = it->second[i];
      if (cellText(cells[0]) == cellText(k.type) && cellText(cells[1]) == cellText(k.def) &&
          cellText(cells[2]) == cellText(k.range)) {
        found = true;
        matched.insert({key, i});
      }
    }
    std::string tables;
    for (const KeyDoc& k : it->second)
      tables +=
          "\n  " + std::string(k.type) + " | " + std::string(k.def) + " | " + std::string(k.range);
    EXPECT_TRUE(found) << "render." << key << ": the docs say\n  " << cellText(cells[0]) << " | "
                       << cellText(cells[1]) << " | " << cellText(cells[2]) << "\nbut the key table"
                       << (it->second.size() > 1 ? "s say" : " says") << tables;
  }
  EXPECT_GT(rows, 50) << "the render key tables of docs/scene-format.md were not found";
  for (const auto& [key, list] : code)
    for (std::size_t i = 0; i < list.size(); ++i)
      EXPECT_TRUE(matched.count({key, i}))
          << "render." << key << " (" << list[i].def << ") has no row in docs/scene-format.md";
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
