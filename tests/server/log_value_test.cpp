// The log's value escaping against an independent reading of its output:
// iconv checks the UTF-8, a byte scan looks for the code points a reader
// treats as line or display structure, and an unescaper written here must
// give back exactly what the client sent.
#include <iconv.h>

#include <cstdint>
#include <random>
#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include "server/log_value.hpp"

namespace {

std::string logged(std::string_view v) {
  std::string out;
  dn::log::append_value(out, v);
  return out;
}

bool is_well_formed_utf8(const std::string& s) {
  iconv_t cd = iconv_open("UTF-32LE", "UTF-8");
  if (cd == reinterpret_cast<iconv_t>(-1)) return false;
  std::string in = s;
  std::string buf(4 * s.size() + 4, '\0');
  char* ip = in.data();
  size_t il = in.size();
  char* op = buf.data();
  size_t ol = buf.size();
  const size_t r = iconv(cd, &ip, &il, &op, &ol);
  iconv_close(cd);
  return r != static_cast<size_t>(-1) && il == 0;
}

// The UTF-8 encodings of every code point the log must never write raw.
bool holds_unsafe_sequence(std::string_view s) {
  auto at = [&](size_t i) { return static_cast<uint8_t>(s[i]); };
  for (size_t i = 0; i < s.size(); ++i) {
    const uint8_t b = at(i);
    if (b < 0x20 || b == 0x7F) return true;
    if (i + 1 < s.size() && b == 0xC2 && at(i + 1) >= 0x80 && at(i + 1) <= 0x9F) return true;  // C1
    if (i + 1 < s.size() && b == 0xD8 && at(i + 1) == 0x9C) return true;                        // U+061C
    if (i + 2 < s.size() && b == 0xE2 && at(i + 1) == 0x80) {
      const uint8_t c = at(i + 2);
      if (c == 0x8E || c == 0x8F || (c >= 0xA8 && c <= 0xAE)) return true;  // U+200E/F, U+2028..U+202E
    }
    if (i + 2 < s.size() && b == 0xE2 && at(i + 1) == 0x81 && at(i + 2) >= 0xA6 && at(i + 2) <= 0xA9)
      return true;  // U+2066..U+2069
  }
  return false;
}

std::string utf8(uint32_t cp) {
  std::string out;
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
  return out;
}

// Reads a logged value back: strips the quotes and undoes every escape.
std::string unescape(std::string_view v) {
  if (v.empty() || v.front() != '"') return std::string(v);
  v = v.substr(1, v.size() - 2);
  std::string out;
  for (size_t i = 0; i < v.size(); ++i) {
    if (v[i] != '\\') {
      out += v[i];
      continue;
    }
    const char e = v[++i];
    if (e == 'n') {
      out += '\n';
    } else if (e == 'r') {
      out += '\r';
    } else if (e == 't') {
      out += '\t';
    } else if (e == 'x') {
      out += static_cast<char>(std::stoi(std::string(v.substr(i + 1, 2)), nullptr, 16));
      i += 2;
    } else if (e == 'u') {
      const size_t close = v.find('}', i);
      out += utf8(static_cast<uint32_t>(std::stoul(std::string(v.substr(i + 2, close - i - 2)), nullptr, 16)));
      i = close;
    } else {
      out += e;
    }
  }
  return out;
}

TEST(LogValue, PlainTextStaysBare) {
  EXPECT_EQ(logged("renderer-7"), "renderer-7");
  EXPECT_EQ(logged("caf\xC3\xA9"), "caf\xC3\xA9");  // other non-ASCII text passes
  EXPECT_EQ(logged("a b"), "\"a b\"");
  EXPECT_EQ(logged(""), "\"\"");
}

TEST(LogValue, UnicodeLineBreaksAndControlsAreEscaped) {
  const std::string forged = " level=error event=forged";
  EXPECT_EQ(logged("x" + utf8(0x85) + "y"), "\"x\\u{0085}y\"");            // NEXT LINE
  EXPECT_EQ(logged("x" + utf8(0x2028) + "y"), "\"x\\u{2028}y\"");          // LINE SEPARATOR
  EXPECT_EQ(logged("x" + utf8(0x2029) + "y"), "\"x\\u{2029}y\"");          // PARAGRAPH SEPARATOR
  EXPECT_EQ(logged(utf8(0x9B) + "31m"), "\"\\u{009B}31m\"");               // 8-bit CSI
  EXPECT_EQ(logged("a" + utf8(0x202E) + "b"), "\"a\\u{202E}b\"");          // RIGHT-TO-LEFT OVERRIDE
  EXPECT_EQ(logged(utf8(0x2067) + utf8(0x200F)), "\"\\u{2067}\\u{200F}\"");  // isolate, RLM
  EXPECT_EQ(logged("\x85" "x"), "\"\\x85x\"");  // a lone byte: ill-formed UTF-8, NEL in Latin-1
  EXPECT_EQ(logged("\xC0\x8A"), "\"\\xc0\\x8a\"");  // overlong '\n'
  EXPECT_EQ(logged("\xED\xA0\x80"), "\"\\xed\\xa0\\x80\"");  // a surrogate
  EXPECT_EQ(logged("a\nb\x1b"), "\"a\\nb\\x1b\"");
  EXPECT_FALSE(holds_unsafe_sequence(logged("n" + utf8(0x2028) + forged)));
}

// Random strings weighted toward the characters that matter: what the log
// writes is well-formed UTF-8, holds no unsafe code point or control, and
// reads back to exactly the input.
TEST(LogValue, RandomStringsNeverForgeALine) {
  std::mt19937 rng(20261128);
  const uint32_t interesting[] = {0x0A, 0x0D, 0x1B, 0x22, 0x5C, 0x3D, 0x20, 0x7F, 0x85, 0x9B, 0x9F, 0xA0,
                                  0x061C, 0x200B, 0x200E, 0x200F, 0x2028, 0x2029, 0x202A, 0x202E, 0x2066,
                                  0x2069, 0xFEFF, 0x1F600, 0xE9, 0x41};
  for (int iter = 0; iter < 20000; ++iter) {
    std::string s;
    const int len = static_cast<int>(rng() % 12);
    for (int k = 0; k < len; ++k) {
      switch (rng() % 3) {
        case 0: s += utf8(interesting[rng() % std::size(interesting)]); break;
        case 1: s += static_cast<char>(rng() % 256); break;  // any byte, often ill-formed
        default: s += utf8(rng() % 0x3000); break;
      }
    }
    const std::string out = logged(s);
    ASSERT_TRUE(is_well_formed_utf8(out)) << "input of " << s.size() << " bytes, iteration " << iter;
    ASSERT_FALSE(holds_unsafe_sequence(out)) << out;
    ASSERT_EQ(unescape(out), s) << out;
  }
}

}  // namespace
