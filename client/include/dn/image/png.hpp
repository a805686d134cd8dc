// A minimal PNG encoder (8-bit RGB, filter type 0, zlib-compressed IDAT):
// enough for previews without a libpng dependency.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace dn::image {

// Encodes width*height*3 bytes of 8-bit sRGB, rows top-first, into a PNG file image.
std::vector<uint8_t> encode_png_rgb8(int width, int height, const uint8_t* rgb);
// Writes it; throws ImageError naming the file.
void write_png_rgb8(const std::string& path, int width, int height, const uint8_t* rgb);

}  // namespace dn::image
