#include "session/frame_planes.hpp"

#include <stdexcept>


namespace dn::server {
namespace {

std::string format_name(protocol::Format f) { return f == protocol::Format::F16 ? "fp16" : "fp32"; }

std::array<float, 2> motion_scale(protocol::MotionConvention convention, const pipelines::SessionConfig& config) {
  switch (convention) {
    case protocol::MotionConvention::PixelsToPrevious:
      return {1.0f, 1.0f};
    case protocol::MotionConvention::PixelsToNext:
      return {-1.0f, -1.0f};
    case protocol::MotionConvention::UvToPrevious:
      return {static_cast<float>(config.width), static_cast<float>(config.height)};
  }
  throw std::invalid_argument("unknown motion convention");
}

}  // namespace

std::variant<pipelines::FrameInput, PlaneProblem> frame_planes(const protocol::Frame& frame, const pipelines::SessionConfig& config) {
  pipelines::FrameInput input;
  input.planes.resize(config.channels.size());
  std::vector<bool> seen(config.channels.size(), false);
  for (size_t i = 0; i < frame.planes.size(); ++i) {
    const protocol::PlaneView& plane = frame.planes[i];
    const std::string field = "FRAME.planes[" + std::to_string(i) + "]";
    const protocol::ChannelInfo* info = protocol::find_channel(plane.id);
    const std::string name = info ? std::string(info->name) : "#" + std::to_string(static_cast<int>(plane.id));
    size_t index = config.channels.size();
    for (size_t c = 0; c < config.channels.size(); ++c)
      if (config.channels[c].id == plane.id) index = c;
    if (index == config.channels.size() || !info)
      return PlaneProblem{false, field + ".channel", "channel '" + name + "' was not declared when the session was opened"};
    if (seen[index]) return PlaneProblem{false, field + ".channel", "channel '" + name + "' sent twice"};
    seen[index] = true;
    const protocol::Format declared = config.channels[index].format;
    if (plane.format != declared)
      return PlaneProblem{false, field + ".format",
                          "channel '" + name + "' was declared " + format_name(declared) + " but sent as " +
                              format_name(plane.format)};
    const uint64_t expected = protocol::plane_bytes(*info, declared, config.width, config.height);
    if (plane.bytes.size() != expected)
      return PlaneProblem{false, field + ".byte_length",
                          "channel '" + name + "' has " + std::to_string(plane.bytes.size()) + " bytes, expected " +
                              std::to_string(expected) + " (" + std::to_string(config.width) + "x" +
                              std::to_string(config.height) + "x" + std::to_string(info->components) + ")"};
    input.planes[index] = plane.bytes;
  }
  for (size_t c = 0; c < config.channels.size(); ++c)
    if (!seen[c]) {
      const protocol::ChannelInfo* info = protocol::find_channel(config.channels[c].id);
      return PlaneProblem{true, "FRAME.planes",
                          "channel '" + std::string(info ? info->name : "?") + "' declared at OPEN_SESSION is missing"};
    }
  input.reset = (frame.info.flags & protocol::kFrameReset) != 0;
  input.motion_to_previous_pixels = motion_scale(frame.info.motion, config);
  input.view = frame.info.view;
  input.projection = frame.info.projection;
  return input;
}

pipelines::FrameInput planes_read(pipelines::FrameInput input, const std::vector<pipelines::InputChannel>& declared,
                                  const std::vector<pipelines::InputChannel>& read) {
  if (declared == read) return input;
  std::vector<std::span<const uint8_t>> planes;
  for (const auto& r : read)
    for (size_t d = 0; d < declared.size(); ++d)
      if (declared[d].id == r.id) planes.push_back(input.planes[d]);
  input.planes = std::move(planes);
  return input;
}

pipelines::FrameInput frame_planes_or_throw(const protocol::Frame& frame, const pipelines::SessionConfig& config) {
  auto input = frame_planes(frame, config);
  if (auto* problem = std::get_if<PlaneProblem>(&input)) throw std::invalid_argument(problem->message);
  return std::get<pipelines::FrameInput>(std::move(input));
}

}  // namespace dn::server
