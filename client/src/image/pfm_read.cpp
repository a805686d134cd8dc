// The PFM reader: "PF" / "Pf", either byte order, checked against the file's
// size before anything is allocated for the pixels.
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>

#include "dn/image/exr_io.hpp"  // ImageError
#include "dn/image/pfm.hpp"

namespace dn::image {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw ImageError("PFM '" + path + "': " + what);
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

// The next whitespace-separated header word, at most 32 characters: a header
// word never is longer, and a binary file is not read as one.
std::string next_word(const std::string& bytes, size_t& at) {
  while (at < bytes.size() && is_space(bytes[at])) ++at;
  const size_t begin = at;
  while (at < bytes.size() && !is_space(bytes[at]) && at - begin < 32) ++at;
  return bytes.substr(begin, at - begin);
}

// A word as a message shows it: non-printable bytes as '?'.
std::string printable(std::string word) {
  for (char& c : word)
    if (!std::isprint(static_cast<unsigned char>(c))) c = '?';
  return word;
}

int parse_size(const std::string& path, const std::string& word, const char* what) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(word.c_str(), &end, 10);
  if (word.empty() || end != word.c_str() + word.size() || errno != 0 || v <= 0 ||
      v > std::numeric_limits<int>::max())
    fail(path, std::string("bad ") + what + " '" + printable(word) + "' (expected a positive integer)");
  return int(v);
}

uint32_t byte_swap(uint32_t v) {
  return (v >> 24) | ((v >> 8) & 0xff00u) | ((v << 8) & 0xff0000u) | (v << 24);
}

}  // namespace

std::vector<float> read_pfm_rgb(const std::string& path, int& width, int& height) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot read: ") + std::strerror(errno));
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) fail(path, "cannot read");

  size_t at = 0;
  const std::string magic = next_word(bytes, at);
  if (magic != "PF" && magic != "Pf")
    fail(path, "not a PFM: it starts with '" + printable(magic) + "', expected 'PF' (colour) or 'Pf' (grey)");
  const size_t channels = magic == "PF" ? 3 : 1;
  const int w = parse_size(path, next_word(bytes, at), "width");
  const int h = parse_size(path, next_word(bytes, at), "height");
  const std::string scale_word = next_word(bytes, at);
  char* end = nullptr;
  const double scale = std::strtod(scale_word.c_str(), &end);
  if (scale_word.empty() || end != scale_word.c_str() + scale_word.size() || !std::isfinite(scale) || scale == 0.0)
    fail(path, "bad scale '" + printable(scale_word) + "' (expected a non-zero number; its sign gives the byte order)");

  // The pixels are the file's last w*h*channels floats; one whitespace
  // character (or "\r\n", as some writers put it) separates them from the scale.
  const size_t need = size_t(w) * size_t(h) * channels * sizeof(float);
  const size_t after_header = at + 1;
  if (at >= bytes.size() || bytes.size() - after_header < need)
    fail(path, "truncated: " + std::to_string(w) + "x" + std::to_string(h) + " " + magic + " needs " +
                   std::to_string(need) + " bytes of pixels, the file has " +
                   std::to_string(at >= bytes.size() ? 0 : bytes.size() - after_header));
  const size_t data_at = bytes.size() - need;
  for (size_t i = at; i < data_at; ++i)
    if (!is_space(bytes[i]))
      fail(path, "the file is " + std::to_string(data_at - after_header) + " bytes longer than " + std::to_string(w) +
                     "x" + std::to_string(h) + " " + magic + " pixels need");

  const bool swap = (scale < 0) != (std::endian::native == std::endian::little);
  std::vector<float> rgb(size_t(w) * size_t(h) * 3);
  const char* src = bytes.data() + data_at;
  for (int y = 0; y < h; ++y) {
    // Rows are stored bottom-first.
    float* row = rgb.data() + size_t(h - 1 - y) * size_t(w) * 3;
    for (int x = 0; x < w; ++x)
      for (size_t c = 0; c < 3; ++c) {
        uint32_t bits = 0;
        std::memcpy(&bits, src + (size_t(y) * size_t(w) + size_t(x)) * channels * 4 + (channels == 3 ? c : 0) * 4, 4);
        row[size_t(x) * 3 + c] = std::bit_cast<float>(swap ? byte_swap(bits) : bits);
      }
  }
  width = w;
  height = h;
  return rgb;
}

}  // namespace dn::image
