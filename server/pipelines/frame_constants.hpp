// What every pass sees besides its buffers: the per-frame constants block
// (binding 0, shaders/include/frame.glsl) and the dispatch conventions.
// Depends on nothing else in pipelines/, so graph.cpp and fb_lut.cpp can both
// use it without including each other.
#pragma once

#include <cstdint>

#include "pipelines/parameters.hpp"

namespace dn::pipelines {

// Uniform block of every pass (shaders/include/frame.glsl), std140; the
// spirv.* tests compare every member offset with the shaders'.
struct FrameConstants {
  uint32_t size[4];    // width, height, pixel count, flags
  float motion[4];     // xy: scale from the client's motion vectors to pixels towards the previous frame
  float inverse_view_projection[16];  // (projection * view)^-1 of the frame, column-major: clip -> world
  float previous_view_projection[16];  // projection * view of the previous frame: world -> its clip (identity before one)
  Parameters params;   // last: grows with parameters.def (no slot cap)
};
static_assert(sizeof(FrameConstants) % 16 == 0);

inline constexpr uint32_t kFrameFlagReset = 1u;  // DN_FLAG_RESET
inline constexpr uint32_t kWorkgroupSize = 64;   // specialization constant 0 of every pass

}  // namespace dn::pipelines
