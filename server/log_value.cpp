#include "server/log_value.hpp"

#include <cstdint>
#include <cstdio>

namespace dn::log {
namespace {

// Length of the well-formed UTF-8 sequence at s[i] (RFC 3629: no overlongs, no
// surrogates, nothing above U+10FFFF) and its code point; 0 when ill-formed.
size_t decode_utf8(std::string_view s, size_t i, uint32_t& cp) {
  const auto byte = [&](size_t k) { return static_cast<uint8_t>(s[k]); };
  const uint8_t b0 = byte(i);
  if (b0 < 0x80) {
    cp = b0;
    return 1;
  }
  size_t n = 0;
  uint32_t min = 0;
  if ((b0 & 0xE0) == 0xC0) {
    n = 2, cp = b0 & 0x1F, min = 0x80;
  } else if ((b0 & 0xF0) == 0xE0) {
    n = 3, cp = b0 & 0x0F, min = 0x800;
  } else if ((b0 & 0xF8) == 0xF0) {
    n = 4, cp = b0 & 0x07, min = 0x10000;
  } else {
    return 0;
  }
  if (i + n > s.size()) return 0;
  for (size_t k = 1; k < n; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (byte(i + k) & 0x3F);
  }
  if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
  return n;
}

// Code points a line-splitting or bidi-aware reader treats as structure.
bool is_unsafe_code_point(uint32_t cp) {
  return (cp >= 0x80 && cp <= 0x9F) || cp == 0x061C || cp == 0x200E || cp == 0x200F ||
         (cp >= 0x2028 && cp <= 0x202E) || (cp >= 0x2066 && cp <= 0x2069);
}

bool is_ascii_control(uint8_t c) { return c < 0x20 || c == 0x7F; }

bool needs_quotes(std::string_view v) {
  if (v.empty()) return true;
  for (size_t i = 0; i < v.size();) {
    const auto c = static_cast<uint8_t>(v[i]);
    if (c == ' ' || c == '"' || c == '=' || c == '\\' || is_ascii_control(c)) return true;
    uint32_t cp = 0;
    const size_t n = decode_utf8(v, i, cp);
    if (n == 0 || is_unsafe_code_point(cp)) return true;
    i += n;
  }
  return false;
}

void append_hex_byte(std::string& out, uint8_t c) {
  char hex[5];
  std::snprintf(hex, sizeof hex, "\\x%02x", static_cast<unsigned>(c));
  out += hex;
}

}  // namespace

void append_value(std::string& out, std::string_view v) {
  if (!needs_quotes(v)) {
    out += v;
    return;
  }
  out += '"';
  for (size_t i = 0; i < v.size();) {
    const auto c = static_cast<uint8_t>(v[i]);
    uint32_t cp = 0;
    const size_t n = decode_utf8(v, i, cp);
    if (n == 0) {
      append_hex_byte(out, c);
      i += 1;
      continue;
    }
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c == '\t') {
      out += "\\t";
    } else if (n == 1 && is_ascii_control(c)) {
      append_hex_byte(out, c);
    } else if (is_unsafe_code_point(cp)) {
      char u[12];
      std::snprintf(u, sizeof u, "\\u{%04X}", static_cast<unsigned>(cp));
      out += u;
    } else {
      out.append(v.substr(i, n));
    }
    i += n;
  }
  out += '"';
}

}  // namespace dn::log
