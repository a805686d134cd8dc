#include "dn/image/pfm.hpp"

#include <bit>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>

#include "dn/image/exr_io.hpp"

namespace dn::image {

namespace {

[[noreturn]] void fail(const std::string& what, const std::string& path) {
  throw ImageError(what + " PFM '" + path + "'" + (errno ? std::string(": ") + std::strerror(errno) : ""));
}

uint32_t byte_swap(uint32_t v) {
  return (v >> 24) | ((v >> 8) & 0xff00u) | ((v << 8) & 0xff0000u) | (v << 24);
}

}  // namespace

void write_pfm_rgb(const std::string& path, int width, int height, const float* rgb) {
  errno = 0;
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!f) fail("cannot write", path);
  // The scale's sign gives the byte order: negative is little-endian.
  const bool little = std::endian::native == std::endian::little;
  if (std::fprintf(f.get(), "PF\n%d %d\n%s\n", width, height, little ? "-1.0" : "1.0") < 0) fail("cannot write", path);
  const size_t row = size_t(width) * 3;
  for (int y = height - 1; y >= 0; --y)
    if (std::fwrite(rgb + size_t(y) * row, sizeof(float), row, f.get()) != row) fail("cannot write", path);
  if (std::fclose(f.release()) != 0) fail("cannot write", path);
}

std::vector<float> read_pfm_rgb(const std::string& path, int& width, int& height) {
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("cannot read", path);
  std::string magic;
  double scale = 0;
  in >> magic >> width >> height >> scale;
  errno = 0;
  if (!in || magic != "PF" || width <= 0 || height <= 0 || scale == 0) fail("not a colour", path);
  in.get();  // the single whitespace character after the scale
  const size_t row = size_t(width) * 3;
  std::vector<float> rgb(row * size_t(height));
  for (int y = height - 1; y >= 0; --y)
    if (!in.read(reinterpret_cast<char*>(rgb.data() + size_t(y) * row), std::streamsize(row * sizeof(float))))
      fail("truncated", path);
  const bool file_little = scale < 0;
  if (file_little != (std::endian::native == std::endian::little))
    for (float& v : rgb) v = std::bit_cast<float>(byte_swap(std::bit_cast<uint32_t>(v)));
  return rgb;
}

}  // namespace dn::image
