// The boundary where a client's FRAME becomes a pipeline's input: the
// session checks the frame's planes against its declaration once, here, and
// hands the pipeline the planes in declaration order with the camera and
// motion in one convention. No pipeline sees a protocol frame.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "dn/protocol/messages.hpp"
#include "pipelines/pipeline.hpp"

namespace dn::pipelines {

struct FrameInput {
  // planes[i]: the bytes of channel SessionConfig::channels[i], in its
  // declared format and of its exact size (viewed, not copied).
  std::vector<std::span<const uint8_t>> planes;
  bool reset = false;  // every history starts afresh with this frame
  // The motion plane times this is the offset, in pixels, from a pixel to
  // where its surface was in the previous frame.
  std::array<float, 2> motion_to_previous_pixels = {1.0f, 1.0f};
  // The current frame's unjittered camera, column-major (docs/protocol.md §5.3).
  std::array<float, 16> view{}, projection{};
};

// What is wrong with a frame's planes: the field and a message naming the
// channel; `missing` for a declared channel that was not sent.
struct PlaneProblem {
  bool missing = false;
  std::string field;
  std::string message;
};

// The one check of a frame's planes (each declared channel exactly once, in
// its declared format, of width x height x components) and its input.
std::variant<FrameInput, PlaneProblem> frame_input(const protocol::Frame& frame, const SessionConfig& config);

// For callers that build their own frames (tests, benchmarks, the warm-up):
// frame_input() or std::invalid_argument with the problem's message.
FrameInput frame_input_or_throw(const protocol::Frame& frame, const SessionConfig& config);

}  // namespace dn::pipelines
