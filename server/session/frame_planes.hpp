// Where a client's FRAME becomes a pipeline's input: its planes are checked
// against the session's declaration once (each declared channel exactly
// once, in its declared format, of width x height x components) and the
// motion convention becomes one scale to the previous frame's pixels.
#pragma once

#include <string>
#include <variant>

#include "dn/protocol/messages.hpp"
#include "pipelines/frame_input.hpp"

namespace dn::server {

// What is wrong with a frame's planes: the field and a message naming the
// channel; `missing` for a declared channel that was not sent.
struct PlaneProblem {
  bool missing = false;
  std::string field;
  std::string message;
};

std::variant<pipelines::FrameInput, PlaneProblem> frame_planes(const protocol::Frame& frame,
                                                                const pipelines::SessionConfig& config);

// The planes of `declared` (a frame_planes() result) that the pipeline
// reads, in the order of `read` (a subset of `declared`): for a session
// opened as "auto", whose choice does not read every channel sent.
pipelines::FrameInput planes_read(pipelines::FrameInput input, const std::vector<pipelines::InputChannel>& declared,
                                  const std::vector<pipelines::InputChannel>& read);

// For callers that build their own frames (tests, benchmarks, the warm-up):
// frame_planes() or std::invalid_argument with the problem's message.
pipelines::FrameInput frame_planes_or_throw(const protocol::Frame& frame, const pipelines::SessionConfig& config);

}  // namespace dn::server
