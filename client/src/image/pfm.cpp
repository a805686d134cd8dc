#include "dn/image/pfm.hpp"

#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "dn/image/exr_io.hpp"

namespace dn::image {

namespace {

[[noreturn]] void fail(const std::string& what, const std::string& path) {
  throw ImageError(what + " PFM '" + path + "'" + (errno ? std::string(": ") + std::strerror(errno) : ""));
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

}  // namespace dn::image
