#include "input_image.hpp"

#include <filesystem>

#include "dn/image/exr_io.hpp"
#include "dn/image/pfm.hpp"
#include "dn/image/png_read.hpp"

namespace dn::cli {

namespace {

// The EXR channels of `id`'s three components: its own layer first, then an
// unnamed one, in the component spellings presets.hpp also accepts.
std::vector<float> read_exr_components(const image::ExrReader& exr, protocol::ChannelId id) {
  const std::string layer = std::string(protocol::find_channel(id)->name) + ".";
  std::string tried;
  for (const std::string& prefix : {layer, std::string()})
    for (const char* xyz : {"RGB", "XYZ", "rgb", "xyz"}) {
      const std::vector<std::string> names = {prefix + xyz[0], prefix + xyz[1], prefix + xyz[2]};
      if (exr.has_channel(names[0]) && exr.has_channel(names[1]) && exr.has_channel(names[2])) return exr.read(names);
      tried += (tried.empty() ? "" : ", ") + prefix + "{" + xyz[0] + "," + xyz[1] + "," + xyz[2] + "}";
    }
  throw image::ImageError("EXR '" + exr.path() + "' has none of the channels tried for " +
                          std::string(protocol::find_channel(id)->name) + ": " + tried);
}

}  // namespace

ImageFormat input_format_for(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".pfm" ? ImageFormat::Pfm : ext == ".png" ? ImageFormat::Png : ImageFormat::Exr;
}

std::vector<float> read_reference_rgb(const std::string& path, int& width, int& height) {
  const ImageFormat format = input_format_for(path);
  if (format == ImageFormat::Exr) return image::read_exr_rgb(path, width, height);
  RgbImage img = read_input_image(path, format, protocol::ChannelId::Radiance);
  width = img.width;
  height = img.height;
  return std::move(img.rgb);
}

RgbImage read_input_image(const std::string& path, ImageFormat format, protocol::ChannelId id) {
  RgbImage img;
  switch (format) {
    case ImageFormat::Exr: {
      const image::ExrReader exr(path);
      img.width = exr.width();
      img.height = exr.height();
      img.rgb = read_exr_components(exr, id);
      break;
    }
    case ImageFormat::Pfm:
      img.rgb = image::read_pfm_rgb(path, img.width, img.height);
      break;
    case ImageFormat::Png:
      img.rgb = image::read_png_rgb(path, img.width, img.height,
                                    id == protocol::ChannelId::Normal ? image::PngTransfer::Signed
                                                                      : image::PngTransfer::Srgb);
      break;
  }
  return img;
}

}  // namespace dn::cli
