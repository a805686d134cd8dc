// Portable Float Map (PFM) images: "PF" (RGB) or "Pf" (grey), width height,
// a scale whose sign gives the byte order (negative: little-endian), then
// 32-bit floats with rows bottom-first.
#pragma once

#include <string>
#include <vector>

namespace dn::image {

// Writes width*height RGB floats (rows top-first, as everywhere else here) as
// a little-endian PFM; throws ImageError naming the file.
void write_pfm_rgb(const std::string& path, int width, int height, const float* rgb);
// Reads a colour ("PF") or grey ("Pf", replicated to RGB) PFM of either byte
// order into RGB floats, rows top-first; the scale's magnitude is ignored.
// Throws ImageError naming the file and what was wrong (src/image/pfm_read.cpp).
std::vector<float> read_pfm_rgb(const std::string& path, int& width, int& height);

}  // namespace dn::image
