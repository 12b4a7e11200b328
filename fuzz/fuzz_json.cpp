// libFuzzer target: the strict JSON reader (parseJson) and the Params accessors every scene,
// config and record goes through. Any exception other than scatterlab::Error is a finding, as
// is any sanitizer report. Built and run by scripts/fuzz.sh.

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.h"
#include "core/params.h"

using namespace scatterlab;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  Json doc;
  try {
    doc = parseJson(text, "'fuzz'");
  } catch (const Error&) {
    return 0;
  }
  (void)describeValue(doc);
  if (!doc.is_object()) return 0;
  // Read every key with each accessor: the checks must turn any value into a value or an Error.
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    const std::string& key = it.key();
    const auto attempt = [&](auto&& read) {
      try {
        Params p(doc, "");
        read(p);
      } catch (const Error&) {
      }
    };
    attempt([&](Params& p) { (void)p.real(key); });
    attempt([&](Params& p) { (void)p.integer(key); });
    attempt([&](Params& p) { (void)p.vec3(key); });
    attempt([&](Params& p) { (void)p.rgb(key); });
    attempt([&](Params& p) { (void)p.resolution(key); });
    attempt([&](Params& p) { (void)p.string(key); });
    attempt([&](Params& p) { (void)p.children(key); });
    attempt([&](Params& p) {
      Params c = p.child(key);
      c.finish();
    });
  }
  return 0;
}
