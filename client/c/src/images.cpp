// Shared images: names (OIDN's where OIDN has one, else the protocol's
// channel names from protocol::kChannels), formats and strides, packing the
// inputs into planes and writing the output back with the caller's strides.
#include <climits>
#include <cstring>
#include <string>

#include "dn/protocol/codec.hpp"
#include "handles.hpp"

namespace dn::capi {
namespace {

using protocol::ChannelId;

uint32_t components(DNFormat f) {
  switch (f) {
    case DN_FORMAT_FLOAT: case DN_FORMAT_HALF: return 1;
    case DN_FORMAT_FLOAT2: case DN_FORMAT_HALF2: return 2;
    case DN_FORMAT_FLOAT3: case DN_FORMAT_HALF3: return 3;
    case DN_FORMAT_FLOAT4: case DN_FORMAT_HALF4: return 4;
    default: return 0;
  }
}

bool is_half(DNFormat f) { return f >= DN_FORMAT_HALF && f <= DN_FORMAT_HALF4; }
size_t pixel_bytes(DNFormat f) { return components(f) * (is_half(f) ? 2u : 4u); }

std::string format_name(DNFormat f) {
  static const char* const kFloat[] = {"DN_FORMAT_FLOAT", "DN_FORMAT_FLOAT2", "DN_FORMAT_FLOAT3", "DN_FORMAT_FLOAT4"};
  static const char* const kHalf[] = {"DN_FORMAT_HALF", "DN_FORMAT_HALF2", "DN_FORMAT_HALF3", "DN_FORMAT_HALF4"};
  const uint32_t n = components(f);
  if (n == 0) return "format " + std::to_string(int(f));
  return (is_half(f) ? kHalf : kFloat)[n - 1];
}

std::string formats_for(uint32_t n) {
  return n == 1 ? "DN_FORMAT_FLOAT or DN_FORMAT_HALF"
                : "DN_FORMAT_FLOAT" + std::to_string(n) + " or DN_FORMAT_HALF" + std::to_string(n);
}

std::string accepted_names() {
  std::string out = "color, albedo, normal, output (OIDN's names; color is radiance) and the other protocol channels ";
  bool first = true;
  for (const auto& c : protocol::kChannels) {
    if (c.id == ChannelId::Output || c.id == ChannelId::Albedo || c.id == ChannelId::Normal) continue;
    out += (first ? "" : ", ") + std::string(c.name);
    first = false;
  }
  return out;
}

}  // namespace

ChannelId channel_for_image(const std::string& name) {
  if (name == "color") return ChannelId::Radiance;
  if (const protocol::ChannelInfo* c = protocol::find_channel(name)) return c->id;
  throw CError{DN_ERROR_INVALID_ARGUMENT, "unknown image '" + name + "'; images are " + accepted_names()};
}

std::string image_name(ChannelId id) {
  if (id == ChannelId::Radiance) return "color";
  if (const protocol::ChannelInfo* c = protocol::find_channel(id)) return std::string(c->name);
  return "#" + std::to_string(unsigned(id));
}

protocol::Format wire_format(DNFormat format) { return is_half(format) ? protocol::Format::F16 : protocol::Format::F32; }

std::span<const uint8_t> packed_plane(const Image& image, std::vector<uint8_t>& scratch) {
  const size_t px = pixel_bytes(image.format), row = px * image.width, total = row * image.height;
  if (image.pixel_stride == px && image.row_stride == row) return {image.data, total};
  scratch.resize(total);
  for (uint32_t y = 0; y < image.height; ++y) {
    const uint8_t* src = image.data + y * image.row_stride;
    uint8_t* dst = scratch.data() + y * row;
    if (image.pixel_stride == px) {
      std::memcpy(dst, src, row);
    } else {
      for (uint32_t x = 0; x < image.width; ++x) std::memcpy(dst + x * px, src + x * image.pixel_stride, px);
    }
  }
  return {scratch.data(), total};
}

void write_output(const client::Result& result, const Image& image) {
  if (result.width != image.width || result.height != image.height)
    throw CError{DN_ERROR_PROTOCOL, "the result of frame " + std::to_string(result.frame_index) + " is " +
                                        std::to_string(result.width) + "x" + std::to_string(result.height) +
                                        ", the output image " + std::to_string(image.width) + "x" +
                                        std::to_string(image.height)};
  const size_t n = size_t(image.width) * image.height * 3;
  // The session was opened with the output image's format, so the bytes are
  // copied as they came; a server answering in the other format is converted.
  std::vector<uint8_t> converted;
  const uint8_t* src = result.output.data();
  if (wire_format(image.format) != result.format) {
    if (is_half(image.format)) {
      const std::vector<float> rgb = result.rgb();
      converted.resize(n * 2);
      for (size_t i = 0; i < n; ++i) {
        const uint16_t h = protocol::float_to_half(rgb[i]);
        std::memcpy(converted.data() + 2 * i, &h, 2);
      }
    } else {
      converted.resize(n * 4);
      result.copy_rgb({reinterpret_cast<float*>(converted.data()), n});
    }
    src = converted.data();
  } else if (result.output.size() != n * (is_half(image.format) ? 2 : 4)) {
    throw CError{DN_ERROR_PROTOCOL, "the result of frame " + std::to_string(result.frame_index) + " has " +
                                        std::to_string(result.output.size()) + " output bytes"};
  }
  const size_t px = pixel_bytes(image.format), row = px * image.width;
  for (uint32_t y = 0; y < image.height; ++y) {
    uint8_t* dst = image.data + y * image.row_stride;
    const uint8_t* line = src + y * row;
    if (image.pixel_stride == px) {
      std::memcpy(dst, line, row);
    } else {
      for (uint32_t x = 0; x < image.width; ++x) std::memcpy(dst + x * image.pixel_stride, line + x * px, px);
    }
  }
}

}  // namespace dn::capi

using namespace dn;
using namespace dn::capi;

extern "C" {

DN_API void dnSetSharedFilterImage(DNFilter filter, const char* name, void* devPtr, DNFormat format, size_t width,
                                   size_t height, size_t byteOffset, size_t bytePixelStride, size_t byteRowStride) {
  guarded_filter_void(filter, "dnSetSharedFilterImage", [&](DNFilterImpl& f) {
    Image image;
    image.name = required_name(name);
    image.id = channel_for_image(image.name);
    const std::string what = "image '" + image.name + "'";
    if (!devPtr) throw CError{DN_ERROR_INVALID_ARGUMENT, what + ": the pointer is NULL"};
    const uint32_t n = components(format);
    if (n == 0) throw CError{DN_ERROR_INVALID_ARGUMENT, what + ": " + format_name(format) + " is not a DNFormat"};
    const uint32_t wanted = protocol::find_channel(image.id)->components;
    if (n != wanted)
      throw CError{DN_ERROR_INVALID_ARGUMENT, what + " has " + std::to_string(wanted) + " component" +
                                                  (wanted == 1 ? "" : "s") + ", but " + format_name(format) +
                                                  " has " + std::to_string(n) + ": use " + formats_for(wanted)};
    if (width == 0 || height == 0 || width > UINT32_MAX || height > UINT32_MAX)
      throw CError{DN_ERROR_INVALID_ARGUMENT,
                   what + " is " + std::to_string(width) + "x" + std::to_string(height) + ", not a valid size"};
    image.format = format;
    image.width = uint32_t(width);
    image.height = uint32_t(height);
    const size_t px = pixel_bytes(format);
    image.pixel_stride = bytePixelStride ? bytePixelStride : px;
    if (image.pixel_stride < px)
      throw CError{DN_ERROR_INVALID_ARGUMENT, what + ": bytePixelStride " + std::to_string(bytePixelStride) +
                                                  " is less than the " + std::to_string(px) + " bytes of a " +
                                                  format_name(format) + " pixel"};
    const size_t least_row = (width - 1) * image.pixel_stride + px;
    image.row_stride = byteRowStride ? byteRowStride : width * image.pixel_stride;
    if (image.row_stride < least_row)
      throw CError{DN_ERROR_INVALID_ARGUMENT, what + ": byteRowStride " + std::to_string(byteRowStride) +
                                                  " is less than the " + std::to_string(least_row) +
                                                  " bytes a row of " + std::to_string(width) + " pixels spans"};
    image.data = static_cast<uint8_t*>(devPtr) + byteOffset;
    if (image.id == protocol::ChannelId::Output) f.output = std::move(image);
    else f.inputs[image.id] = std::move(image);  // "color" and "radiance" are one image
  });
}

DN_API void dnUnsetFilterImage(DNFilter filter, const char* name) {
  guarded_filter_void(filter, "dnUnsetFilterImage", [&](DNFilterImpl& f) {
    const protocol::ChannelId id = channel_for_image(required_name(name));
    if (id == protocol::ChannelId::Output) f.output.reset();
    else f.inputs.erase(id);
  });
}

}  // extern "C"
