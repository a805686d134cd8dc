// Portable Float Map (PFM) colour images: "PF", width height, a negative
// scale for little-endian, then 32-bit float RGB with rows bottom-first.
#pragma once

#include <string>
#include <vector>

namespace dn::image {

// Writes width*height RGB floats (rows top-first, as everywhere else here) as
// a little-endian PFM; throws ImageError naming the file.
void write_pfm_rgb(const std::string& path, int width, int height, const float* rgb);
// Reads a colour PFM of either byte order into RGB floats, rows top-first;
// throws ImageError naming the file.
std::vector<float> read_pfm_rgb(const std::string& path, int& width, int& height);

}  // namespace dn::image
