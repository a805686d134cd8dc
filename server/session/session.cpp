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

std::shared_ptr<const std::vector<uint8_t>> encode_shared(const protocol::Message& m, uint64_t request_id) {
  auto bytes = std::make_shared<std::vector<uint8_t>>();
  protocol::encode(m, request_id, 0, *bytes);
  return bytes;
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

FrameDone Session::run(FrameJob& job) {
  FrameDone done;
  done.session_id = id_;
  done.request_id = job.request_id;
  done.frame_index = job.frame.info.frame_index;
  std::vector<uint8_t> output;
  const bool any_watcher = std::find(job.watcher_forms.begin(), job.watcher_forms.end(), true) != job.watcher_forms.end();
  try {
    pipeline_->process(job.frame, job.owner_wants_output || any_watcher, output, done.timings);
  } catch (const std::exception& e) {
    done.failed = true;
    done.owner_message = encode_shared(
        protocol::Error{protocol::ErrorCode::DeviceError, "FRAME", std::string("device failure: ") + e.what()},
        job.request_id);
    return done;
  }

  const std::optional<protocol::SampleCounts> samples = pipeline_->samples();
  const protocol::PlaneView plane{protocol::ChannelId::Output, config_.output_format,
                                  std::span<const uint8_t>(output.data(), output.size())};
  // One RESULT of the given form; the radiance plane is a view into the
  // FRAME's payload, alive until this returns.
  auto encode_form = [&](ResultForm form, bool with_output) {
    protocol::Result result;
    result.session_id = id_;
    result.frame_index = job.frame.info.frame_index;
    result.timings = done.timings;
    if (with_output) result.planes = {plane};
    if (form.input)
      for (const protocol::PlaneView& p : job.frame.planes)
        if (p.id == protocol::ChannelId::Radiance) result.planes.push_back(p);
    if (form.samples) result.samples = samples ? *samples : protocol::SampleCounts{};  // counted false: no count
    return encode_shared(result, job.request_id);
  };
  for (size_t i = 0; i < job.watcher_forms.size(); ++i)
    if (job.watcher_forms[i]) done.watcher_messages[i] = encode_form(ResultForm{i >= 2, (i & 1) != 0}, true);
  const ResultForm owner{false, job.owner_gets_samples};
  if (job.owner_wants_output && done.watcher_messages[owner.index()])
    done.owner_message = done.watcher_messages[owner.index()];  // identical bytes: share them
  else
    done.owner_message = encode_form(owner, job.owner_wants_output);
  return done;
}

}  // namespace dn::server
