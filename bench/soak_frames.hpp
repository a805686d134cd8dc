// The soak's sessions and frames: for any pipeline the server offers, a
// session declaring what it needs and frames of plausible constant planes
// (a grey wall one metre away) whose radiance changes with the frame index.
#pragma once

#include <cstdint>
#include <vector>

#include "dn/client/client.hpp"

namespace dn::soak {

// The pipeline's required channels, plus radiance where it is optional and no
// split form is required (as the server's warm-up does), diffuse where
// specular is required, and sample_count where it is taken; all fp32.
client::SessionDesc session_for(const protocol::PipelineInfo& pipeline, uint32_t width, uint32_t height,
                                uint32_t in_flight);

// Planes for every channel a session declares; frame() rewrites the radiance
// from the frame index so each frame differs.
class FramePlanes {
 public:
  explicit FramePlanes(const client::SessionDesc& desc);
  client::FrameInput frame(uint64_t index);

 private:
  struct Plane {
    protocol::ChannelId id;
    std::vector<float> values;
  };
  std::vector<Plane> planes_;
};

}  // namespace dn::soak
