#include "colour_frames.hpp"

#include "input_image.hpp"
#include "presets.hpp"  // ChannelMapError

namespace dn::cli {

using protocol::ChannelId;

LoadedFrame load_colour_frame(const std::string& pattern, ImageFormat format, long long number) {
  LoadedFrame f;
  f.number = number;
  f.path = format_frame_path(pattern, number);
  RgbImage img = read_input_image(f.path, format, ChannelId::Radiance);
  f.width = img.width;
  f.height = img.height;
  f.planes.push_back({ChannelId::Radiance, std::move(img.rgb)});
  return f;
}

std::vector<ChannelId> plan_colour_channels(const protocol::PipelineInfo* pipeline, const std::string& pipeline_name,
                                            const std::vector<SideFile>& sides, const std::string& first_path) {
  std::vector<ChannelId> ids = {ChannelId::Radiance};
  for (const auto& s : sides) ids.push_back(s.id);
  if (!pipeline) return ids;
  uint64_t given = 0;
  for (ChannelId id : ids) given |= protocol::channel_bit(id);
  for (const auto& c : protocol::kChannels) {
    if (!(pipeline->required_channels & ~given & protocol::channel_bit(c.id))) continue;
    const std::string name(c.name);
    const std::string hint = c.id == ChannelId::Albedo   ? "give it with --albedo FILE"
                             : c.id == ChannelId::Normal ? "give it with --normal FILE"
                                                         : "it needs an EXR input that has it";
    throw ChannelMapError("pipeline '" + pipeline_name + "' requires channel '" + name + "', but " + first_path +
                          " gives only the colour (radiance); " + hint);
  }
  return ids;
}

}  // namespace dn::cli
