// The channel set the benchmarks send: what SVGF needs with split lighting.
#pragma once

#include <cstring>
#include <random>
#include <vector>

#include "dn/protocol/codec.hpp"

namespace dn::bench {

inline std::vector<protocol::ChannelDecl> svgf_channels(protocol::Format format) {
  using protocol::ChannelId;
  std::vector<protocol::ChannelDecl> c;
  for (ChannelId id : {ChannelId::Radiance, ChannelId::Diffuse, ChannelId::Specular, ChannelId::Albedo,
                       ChannelId::Normal, ChannelId::Depth, ChannelId::Motion, ChannelId::Emission})
    c.push_back({id, format});
  return c;
}

struct FrameData {
  std::vector<std::vector<uint8_t>> planes;
  protocol::Frame frame;
};

inline FrameData make_frame(uint32_t width, uint32_t height, const std::vector<protocol::ChannelDecl>& channels) {
  FrameData f;
  std::mt19937 rng(7);
  f.planes.reserve(channels.size());
  for (const auto& c : channels) {
    const auto& info = *protocol::find_channel(c.id);
    std::vector<uint8_t> bytes(protocol::plane_bytes(info, c.format, width, height));
    // Random bytes would include NaNs; fill with finite values in [0, 1).
    for (size_t i = 0; i + 4 <= bytes.size(); i += 4) {
      float v = static_cast<float>(rng() >> 8) * (1.0f / 16777216.0f);
      if (c.format == protocol::Format::F32) {
        std::memcpy(&bytes[i], &v, 4);
      } else {
        uint16_t h = protocol::float_to_half(v);
        std::memcpy(&bytes[i], &h, 2);
        std::memcpy(&bytes[i + 2], &h, 2);
      }
    }
    f.planes.push_back(std::move(bytes));
    f.frame.planes.push_back({c.id, c.format, std::span<const uint8_t>(f.planes.back())});
  }
  for (int i = 0; i < 4; ++i) f.frame.info.view[i * 5] = f.frame.info.projection[i * 5] = 1.0f;
  f.frame.info.prev_view = f.frame.info.view;
  f.frame.info.prev_projection = f.frame.info.projection;
  return f;
}

}  // namespace dn::bench
