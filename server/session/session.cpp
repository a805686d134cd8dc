#include "server/session/session.hpp"

#include <algorithm>
#include <string>

#include "dn/protocol/codec.hpp"

namespace dn::server {

uint64_t frame_message_bytes(const pipelines::SessionConfig& config) {
  uint64_t bytes = 4096;
  for (const auto& ch : config.channels)
    bytes += protocol::plane_bytes(*protocol::find_channel(ch.id), ch.format, config.width, config.height) + 16;
  return bytes;
}

namespace {

protocol::Error make_error(protocol::ErrorCode code, std::string field, std::string message) {
  return protocol::Error{code, std::move(field), std::move(message)};
}

}  // namespace

Session::Session(uint64_t id, uint64_t owner, pipelines::SessionConfig config,
                 std::unique_ptr<pipelines::Pipeline> pipeline, std::string watch_key)
    : id_(id),
      owner_(owner),
      watch_key_(std::move(watch_key)),
      config_(std::move(config)),
      pipeline_(std::move(pipeline)) {
  device_bytes_ = pipeline_ ? pipeline_->device_bytes() : 0;
  transient_bytes_ = pipeline_ ? pipeline_->transient_bytes() : 0;
}

Session::~Session() = default;

std::optional<protocol::Error> Session::check_frame(const protocol::Frame& frame) const {
  using protocol::ErrorCode;
  if (last_frame_index && frame.info.frame_index <= *last_frame_index)
    return make_error(ErrorCode::OutOfOrder, "FRAME.frame_index",
                      "frame_index " + std::to_string(frame.info.frame_index) + " is not above the last frame " +
                          std::to_string(*last_frame_index) + " of session " + std::to_string(id_));

  std::vector<bool> seen(config_.channels.size(), false);
  for (size_t i = 0; i < frame.planes.size(); ++i) {
    const protocol::PlaneView& plane = frame.planes[i];
    const std::string field = "FRAME.planes[" + std::to_string(i) + "]";
    const protocol::ChannelInfo* info = protocol::find_channel(plane.id);
    std::string name = info ? std::string(info->name) : "#" + std::to_string(static_cast<int>(plane.id));
    size_t index = config_.channels.size();
    for (size_t c = 0; c < config_.channels.size(); ++c)
      if (config_.channels[c].id == plane.id) index = c;
    if (index == config_.channels.size() || !info)
      return make_error(ErrorCode::InvalidChannel, field + ".channel",
                        "channel '" + name + "' was not declared when session " + std::to_string(id_) + " was opened");
    if (seen[index])
      return make_error(ErrorCode::InvalidChannel, field + ".channel", "channel '" + name + "' sent twice");
    seen[index] = true;
    const protocol::Format declared = config_.channels[index].format;
    if (plane.format != declared)
      return make_error(ErrorCode::InvalidChannel, field + ".format",
                        "channel '" + name + "' was declared " + (declared == protocol::Format::F16 ? "fp16" : "fp32") +
                            " but sent as " + (plane.format == protocol::Format::F16 ? "fp16" : "fp32"));
    const uint64_t expected = protocol::plane_bytes(*info, declared, config_.width, config_.height);
    if (plane.bytes.size() != expected)
      return make_error(ErrorCode::InvalidChannel, field + ".byte_length",
                        "channel '" + name + "' has " + std::to_string(plane.bytes.size()) + " bytes, expected " +
                            std::to_string(expected) + " (" + std::to_string(config_.width) + "x" +
                            std::to_string(config_.height) + "x" + std::to_string(info->components) + ")");
  }
  for (size_t c = 0; c < config_.channels.size(); ++c)
    if (!seen[c]) {
      const protocol::ChannelInfo* info = protocol::find_channel(config_.channels[c].id);
      return make_error(ErrorCode::MissingChannel, "FRAME.planes",
                        "channel '" + std::string(info ? info->name : "?") + "' declared at OPEN_SESSION is missing");
    }
  return std::nullopt;
}

FrameOutcome Session::run(const FrameJob& job) {
  FrameOutcome outcome;
  try {
    pipeline_->process(job.frame, job.anyone_wants_output(), outcome.output, outcome.timings);
  } catch (const std::exception& e) {
    outcome.error = e.what();
    return outcome;
  }
  outcome.samples = pipeline_->samples();
  return outcome;
}

}  // namespace dn::server
