// The log's value escaping: whatever bytes a client sends as a name or field,
// the logged value is one well-formed UTF-8 token with no control character,
// no C1 control, no line or paragraph separator and no bidirectional mark.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "server/log_value.hpp"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  std::string out;
  dn::log::append_value(out, in);
  const auto at = [&](size_t i) { return static_cast<uint8_t>(out[i]); };
  const bool quoted = out.size() >= 2 && out.front() == '"' && out.back() == '"';
  for (size_t i = 0; i < out.size();) {
    const uint8_t b = at(i);
    check(b >= 0x20 && b != 0x7F);
    check(quoted || (b != ' ' && b != '"' && b != '='));
    if (b < 0x80) {
      ++i;
      continue;
    }
    // Only well-formed sequences of safe code points may be copied through.
    size_t n = (b & 0xE0) == 0xC0 ? 2 : (b & 0xF0) == 0xE0 ? 3 : (b & 0xF8) == 0xF0 ? 4 : 0;
    check(n != 0 && i + n <= out.size());
    uint32_t cp = b & (0xFF >> (n + 1));
    for (size_t k = 1; k < n; ++k) {
      check((at(i + k) & 0xC0) == 0x80);
      cp = (cp << 6) | (at(i + k) & 0x3F);
    }
    const uint32_t min = n == 2 ? 0x80 : n == 3 ? 0x800 : 0x10000;
    check(cp >= min && cp <= 0x10FFFF && !(cp >= 0xD800 && cp <= 0xDFFF));
    check(!(cp <= 0x9F) && cp != 0x061C && cp != 0x200E && cp != 0x200F && !(cp >= 0x2028 && cp <= 0x202E) &&
          !(cp >= 0x2066 && cp <= 0x2069));
    i += n;
  }
  return 0;
}
