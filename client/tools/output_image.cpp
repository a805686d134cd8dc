#include "output_image.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "args.hpp"
#include "dn/image/pfm.hpp"
#include "dn/image/png.hpp"

namespace dn::cli {

const char* accepted_image_extensions() { return ".exr, .png or .pfm"; }

ImageFormat image_format_for(const std::string& path, const std::string& option) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".exr") return ImageFormat::Exr;
  if (ext == ".png") return ImageFormat::Png;
  if (ext == ".pfm") return ImageFormat::Pfm;
  throw UsageError(option + " '" + path + "': " +
                   (ext.empty() ? std::string("no file extension") : "unknown extension '" + ext + "'") +
                   "; the format follows the extension: " + accepted_image_extensions());
}

void write_image(const std::string& path, ImageFormat format, int width, int height, const float* rgb,
                 const ImageWriteOptions& options) {
  if (const auto parent = std::filesystem::path(path).parent_path(); !parent.empty()) {
    std::error_code ec;  // a failure shows as the write's own error, which names the file
    std::filesystem::create_directories(parent, ec);
  }
  switch (format) {
    case ImageFormat::Exr:
      image::write_exr_rgb(path, width, height, rgb, options.exr_pixels);
      return;
    case ImageFormat::Png: {
      const auto bytes = image::to_srgb8(rgb, size_t(width) * size_t(height), options.tonemap, options.exposure);
      image::write_png_rgb8(path, width, height, bytes.data());
      return;
    }
    case ImageFormat::Pfm:
      image::write_pfm_rgb(path, width, height, rgb);
      return;
  }
}

}  // namespace dn::cli
