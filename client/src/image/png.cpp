#include "dn/image/png.hpp"

#include <zlib.h>

#include <cstdio>
#include <cstring>
#include <memory>

#include "dn/image/exr_io.hpp"  // ImageError

namespace dn::image {

namespace {

void put_u32_be(std::vector<uint8_t>& out, uint32_t v) {
  out.push_back(uint8_t(v >> 24));
  out.push_back(uint8_t(v >> 16));
  out.push_back(uint8_t(v >> 8));
  out.push_back(uint8_t(v));
}

// length, type, data, CRC-32 over type + data.
void put_chunk(std::vector<uint8_t>& out, const char type[4], const uint8_t* data, size_t size) {
  put_u32_be(out, uint32_t(size));
  const size_t type_at = out.size();
  out.insert(out.end(), type, type + 4);
  if (size) out.insert(out.end(), data, data + size);
  uLong crc = crc32(0L, Z_NULL, 0);
  crc = crc32_z(crc, out.data() + type_at, 4 + size);
  put_u32_be(out, uint32_t(crc));
}

}  // namespace

std::vector<uint8_t> encode_png_rgb8(int width, int height, const uint8_t* rgb) {
  if (width <= 0 || height <= 0) throw ImageError("cannot encode PNG: empty image");
  // Scanlines, each prefixed with filter type 0 (None).
  const size_t row = size_t(width) * 3;
  std::vector<uint8_t> raw((row + 1) * size_t(height));
  for (int y = 0; y < height; ++y) {
    uint8_t* dst = raw.data() + size_t(y) * (row + 1);
    dst[0] = 0;
    std::memcpy(dst + 1, rgb + size_t(y) * row, row);
  }
  uLongf zsize = compressBound(uLong(raw.size()));
  std::vector<uint8_t> z(zsize);
  if (compress2(z.data(), &zsize, raw.data(), uLong(raw.size()), 6) != Z_OK)
    throw ImageError("cannot encode PNG: zlib compress2 failed");
  z.resize(zsize);

  std::vector<uint8_t> out;
  out.reserve(z.size() + 64);
  static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  out.insert(out.end(), kSignature, kSignature + 8);
  std::vector<uint8_t> ihdr;
  put_u32_be(ihdr, uint32_t(width));
  put_u32_be(ihdr, uint32_t(height));
  ihdr.push_back(8);  // bit depth
  ihdr.push_back(2);  // colour type: truecolour (RGB)
  ihdr.push_back(0);  // compression: deflate
  ihdr.push_back(0);  // filter method 0
  ihdr.push_back(0);  // no interlace
  put_chunk(out, "IHDR", ihdr.data(), ihdr.size());
  // sRGB chunk: rendering intent perceptual, so viewers do not guess.
  const uint8_t srgb = 0;
  put_chunk(out, "sRGB", &srgb, 1);
  put_chunk(out, "IDAT", z.data(), z.size());
  put_chunk(out, "IEND", nullptr, 0);
  return out;
}

void write_png_rgb8(const std::string& path, int width, int height, const uint8_t* rgb) {
  std::vector<uint8_t> bytes = encode_png_rgb8(width, height, rgb);
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!f) throw ImageError("cannot write PNG '" + path + "': " + std::strerror(errno));
  if (std::fwrite(bytes.data(), 1, bytes.size(), f.get()) != bytes.size())
    throw ImageError("cannot write PNG '" + path + "': " + std::strerror(errno));
  if (std::fclose(f.release()) != 0) throw ImageError("cannot write PNG '" + path + "': " + std::strerror(errno));
}

}  // namespace dn::image
