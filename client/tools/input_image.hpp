// dn denoise's images read without a channel layout: the colour of a PFM or
// PNG input and the --albedo / --normal side files, by extension (EXR, PFM,
// PNG), as RGB floats in the protocol channel's convention.
#pragma once

#include <string>
#include <vector>

#include "dn/protocol/channels.hpp"
#include "output_image.hpp"  // ImageFormat

namespace dn::cli {

struct RgbImage {
  int width = 0, height = 0;
  std::vector<float> rgb;  // interleaved, rows top-first
};

// Reads `path` as the values of protocol channel `id` (radiance, albedo or normal):
//  - PNG: colour and albedo are sRGB-encoded, made linear with the sRGB EOTF;
//    a normal's v in [0, 1] is 2v - 1 (a normal map's encoding, not sRGB).
//  - PFM: as stored (grey replicated to RGB).
//  - EXR: the layer named after the channel (albedo.R/G/B, normal.X/Y/Z, in
//    either case), else R,G,B, else X,Y,Z.
// Throws image::ImageError naming the file and what was wrong.
RgbImage read_input_image(const std::string& path, ImageFormat format, protocol::ChannelId id);

// An input's or a reference's format: .pfm and .png by extension (any case);
// anything else is EXR.
ImageFormat input_format_for(const std::string& path);

// A reference frame's linear RGB (-r, --reference2): an EXR as
// image::read_exr_rgb reads it, a PFM or PNG as read_input_image reads radiance.
std::vector<float> read_reference_rgb(const std::string& path, int& width, int& height);

}  // namespace dn::cli
