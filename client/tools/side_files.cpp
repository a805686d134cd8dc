#include "side_files.hpp"

#include <algorithm>
#include <stdexcept>

#include "input_image.hpp"

namespace dn::cli {

using protocol::ChannelId;

std::vector<SideFile> side_files_from(const Args& args, bool input_is_sequence) {
  std::vector<SideFile> sides;
  for (const auto& [name, id] : {std::pair{"albedo", ChannelId::Albedo}, std::pair{"normal", ChannelId::Normal}}) {
    const auto pattern = args.get(name);
    if (!pattern) continue;
    const std::string option = std::string("--") + name;
    if (!input_is_sequence && has_frame_placeholder(*pattern))
      throw UsageError(option + " '" + *pattern +
                       "' has a frame-number placeholder, but the input is a single file: give one file");
    sides.push_back({id, option, *pattern, image_format_for(*pattern, option)});
  }
  return sides;
}

bool is_side_channel(const std::vector<SideFile>& sides, ChannelId id) {
  return std::any_of(sides.begin(), sides.end(), [&](const SideFile& s) { return s.id == id; });
}

void check_side_channels(const protocol::PipelineInfo* pipeline, const std::vector<SideFile>& sides,
                         const std::string& pipeline_name) {
  if (!pipeline) return;
  for (const auto& s : sides) {
    const uint64_t bit = protocol::channel_bit(s.id);
    if (!((pipeline->required_channels | pipeline->optional_channels) & bit))
      throw UsageError(s.option + ": pipeline '" + pipeline_name + "' does not take the " +
                       std::string(protocol::find_channel(s.id)->name) + " channel (see 'dn pipelines')");
  }
}

protocol::PipelineInfo without_side_channels(protocol::PipelineInfo pipeline, const std::vector<SideFile>& sides) {
  for (const auto& s : sides) {
    pipeline.required_channels &= ~protocol::channel_bit(s.id);
    pipeline.optional_channels &= ~protocol::channel_bit(s.id);
  }
  return pipeline;
}

void add_side_planes(LoadedFrame& frame, const std::vector<SideFile>& sides) {
  for (const auto& s : sides) {
    const std::string path = format_frame_path(s.pattern, frame.number);
    RgbImage img = read_input_image(path, s.format, s.id);
    if (img.width != frame.width || img.height != frame.height)
      throw std::runtime_error(s.option + ": " + path + " is " + std::to_string(img.width) + "x" +
                               std::to_string(img.height) + ", but the input " + frame.path + " is " +
                               std::to_string(frame.width) + "x" + std::to_string(frame.height));
    std::erase_if(frame.planes, [&](const LoadedPlane& p) { return p.id == s.id; });
    frame.planes.push_back({s.id, std::move(img.rgb)});
  }
}

}  // namespace dn::cli
