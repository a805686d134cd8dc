// Output images of dn denoise and dn watch: the format follows the path's
// extension (.exr, .png, .pfm; any case), checked before any server work.
#pragma once

#include <string>

#include "dn/image/exr_io.hpp"
#include "dn/image/metrics.hpp"

namespace dn::cli {

enum class ImageFormat { Exr, Png, Pfm };

// The accepted extensions, for messages and --help: ".exr, .png or .pfm".
const char* accepted_image_extensions();

// The format of `path` (a file name or a frame pattern) by its extension.
// Throws UsageError naming `option` and the accepted extensions otherwise.
ImageFormat image_format_for(const std::string& path, const std::string& option);

struct ImageWriteOptions {
  image::ExrPixelType exr_pixels = image::ExrPixelType::Half;
  image::Tonemap tonemap = image::Tonemap::Aces;  // PNG only: 8-bit sRGB after tone mapping
  float exposure = 1.0f;
};

// Writes width*height interleaved RGB floats (rows top-first) to `path`,
// creating its directory: EXR (half or float), PNG (tone-mapped) or PFM (float).
void write_image(const std::string& path, ImageFormat format, int width, int height, const float* rgb,
                 const ImageWriteOptions& options);

}  // namespace dn::cli
