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

Session::Session(uint64_t id, uint64_t owner, const pipelines::PreparedPipeline& prepared,
                 std::unique_ptr<pipelines::Pipeline> pipeline, std::string watch_key)
    : id_(id),
      owner_(owner),
      watch_key_(std::move(watch_key)),
      config_(prepared.config()),
      frame_config_(prepared.frame_config()),
      choice_reason_(prepared.choice_reason()),
      pipeline_(std::move(pipeline)) {
  device_bytes_ = pipeline_ ? pipeline_->device_bytes() : 0;
  transient_bytes_ = pipeline_ ? pipeline_->transient_bytes() : 0;
}

Session::~Session() = default;

std::variant<pipelines::FrameInput, protocol::Error> Session::check_frame(const protocol::Frame& frame) const {
  using protocol::ErrorCode;
  if (last_frame_index && frame.info.frame_index <= *last_frame_index)
    return make_error(ErrorCode::OutOfOrder, "FRAME.frame_index",
                      "frame_index " + std::to_string(frame.info.frame_index) + " is not above the last frame " +
                          std::to_string(*last_frame_index) + " of session " + std::to_string(id_));
  auto input = frame_planes(frame, frame_config_);
  if (auto* problem = std::get_if<PlaneProblem>(&input))
    return make_error(problem->missing ? ErrorCode::MissingChannel : ErrorCode::InvalidChannel, problem->field,
                      "session " + std::to_string(id_) + ": " + problem->message);
  return planes_read(std::get<pipelines::FrameInput>(std::move(input)), frame_config_.channels, config_.channels);
}

FrameOutcome Session::run(const FrameJob& job) {
  FrameOutcome outcome;
  try {
    pipeline_->process(job.input, job.anyone_wants_output(), outcome.output, outcome.timings);
  } catch (const std::exception& e) {
    outcome.error = e.what();
    return outcome;
  }
  outcome.samples = pipeline_->samples();
  return outcome;
}

}  // namespace dn::server
