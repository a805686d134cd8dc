#include "soak_frames.hpp"

#include "dn/protocol/channels.hpp"

namespace dn::soak {

using protocol::ChannelId;

client::SessionDesc session_for(const protocol::PipelineInfo& pipeline, uint32_t width, uint32_t height,
                                uint32_t in_flight) {
  uint64_t mask = pipeline.required_channels;
  const uint64_t radiance = protocol::channel_bit(ChannelId::Radiance);
  const uint64_t split = protocol::channel_bit(ChannelId::Diffuse) | protocol::channel_bit(ChannelId::Specular);
  if ((pipeline.optional_channels & radiance) && !(mask & split)) mask |= radiance;
  // A required specular signal comes with its diffuse half (svgf-fb, reflect);
  // a sample count where one is taken (progressive).
  const uint64_t diffuse = protocol::channel_bit(ChannelId::Diffuse);
  if ((mask & protocol::channel_bit(ChannelId::Specular)) && (pipeline.optional_channels & diffuse)) mask |= diffuse;
  mask |= pipeline.optional_channels & protocol::channel_bit(ChannelId::SampleCount);
  client::SessionDesc desc;
  desc.width = width;
  desc.height = height;
  desc.pipeline = pipeline.name;
  desc.max_in_flight = in_flight;
  for (const auto& c : protocol::kChannels)
    if (mask & protocol::channel_bit(c.id)) desc.channel(c.id, protocol::Format::F32);
  return desc;
}

namespace {

// One pixel of `id`: a grey diffuse wall facing the camera at 1 m, rough,
// still (no motion), every pixel sampled, four samples of statistics.
std::vector<float> pixel_of(ChannelId id, uint32_t components) {
  switch (id) {
    case ChannelId::Normal:
    case ChannelId::ReflectionNormal: return {0.0f, 0.0f, 1.0f};
    case ChannelId::ReflectionDirection: return {0.0f, 0.0f, -1.0f};
    case ChannelId::Depth:
    case ChannelId::ReflectionDepth:
    case ChannelId::ReflectionDistance: return {1.0f};
    case ChannelId::Motion: return {0.0f, 0.0f};
    case ChannelId::SampleCount: return {1.0f};
    case ChannelId::StatCount: return {4.0f};
    case ChannelId::StatM2: return {0.1f, 0.1f, 0.1f};
    case ChannelId::StatM3: return {0.0f, 0.0f, 0.0f};
    case ChannelId::ReflectionFootprint: return {0.01f};
    case ChannelId::SpecularF0: return {0.04f, 0.04f, 0.04f};
    default: return std::vector<float>(components, 0.5f);
  }
}

}  // namespace

FramePlanes::FramePlanes(const client::SessionDesc& desc) {
  const size_t pixels = size_t(desc.width) * desc.height;
  for (const auto& decl : desc.channels) {
    const protocol::ChannelInfo* info = protocol::find_channel(decl.id);
    const std::vector<float> pixel = pixel_of(decl.id, info->components);
    Plane p{decl.id, {}};
    p.values.reserve(pixels * pixel.size());
    for (size_t i = 0; i < pixels; ++i) p.values.insert(p.values.end(), pixel.begin(), pixel.end());
    planes_.push_back(std::move(p));
  }
}

client::FrameInput FramePlanes::frame(uint64_t index) {
  client::FrameInput in;
  in.frame_index = index;
  in.info.view = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  in.info.projection = {1, 0, 0, 0, 0, 1.78f, 0, 0, 0, 0, -1, -1, 0, 0, -0.2f, 0};
  if (index == 0) in.reset();
  for (Plane& p : planes_) {
    if (p.id == ChannelId::Radiance || p.id == ChannelId::Diffuse || p.id == ChannelId::StatMean)
      for (float& v : p.values) v = 0.25f + 0.01f * float(index % 50);  // a slow flicker, so frames differ
    in.add(p.id, std::span<const float>(p.values));
  }
  return in;
}

}  // namespace dn::soak
