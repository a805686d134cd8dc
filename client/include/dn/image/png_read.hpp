// A PNG decoder for dn denoise's inputs, on zlib alone (no libpng): every
// non-interlaced PNG — grey, grey + alpha, RGB, RGBA at 8 and 16 bits, grey
// and palette at 1, 2, 4 and 8 bits — to RGB floats, alpha dropped.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace dn::image {

// How a sample v (0 .. 2^bits - 1) becomes a float, with x = v / (2^bits - 1):
// Srgb, the sRGB EOTF of x, for colour (the file's gAMA, cHRM and iCCP chunks
// are not read); Linear, x itself; Signed, 2x - 1, a normal map's encoding
// (computed in double: near 0 a float x would lose the low bits).
enum class PngTransfer { Srgb, Linear, Signed };

// Decodes a PNG file image into width*height RGB floats, rows top-first (grey
// replicated to RGB). Throws ImageError naming `name` and what was wrong: not
// a PNG, truncated, a bad CRC, Adam7 interlacing, an invalid header, ...
std::vector<float> decode_png_rgb(std::span<const uint8_t> png, const std::string& name, int& width, int& height,
                                  PngTransfer transfer = PngTransfer::Srgb);
// Reads and decodes a PNG file; ImageError naming the file.
std::vector<float> read_png_rgb(const std::string& path, int& width, int& height,
                                PngTransfer transfer = PngTransfer::Srgb);

}  // namespace dn::image
