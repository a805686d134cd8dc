// A frame as a pipeline receives it: the session checked its planes against
// the declaration once (server/session/frame_planes.hpp) and hands them over
// in declaration order, with the camera and motion in one convention. No
// pipeline sees a protocol frame.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

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

}  // namespace dn::pipelines
