// What OPEN_SESSION asks for: size, pipeline, output format, parameters and
// the channels every frame will carry.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dn/protocol/messages.hpp"

namespace dn::client {

struct SessionDesc {
  uint32_t width = 0;
  uint32_t height = 0;
  std::string pipeline;
  protocol::Format output_format = protocol::Format::F32;
  std::vector<protocol::Parameter> parameters;
  std::vector<protocol::ChannelDecl> channels;
  // Frames a Session keeps in flight before submit() blocks. 0: the server's
  // WELCOME limits.max_frames_in_flight (3 when the server reports 0). Values
  // above the server's limit are clamped to it.
  uint32_t max_in_flight = 0;
  // Share each frame's noisy radiance with the session's watchers (protocol
  // 1.7, header flag SHARE_INPUT): their Results carry it as `input`, so
  // `dn preview` can show it beside the denoised frame. Needs a radiance channel.
  bool share_input = false;

  SessionDesc& channel(protocol::ChannelId id, protocol::Format format = protocol::Format::F32) {
    channels.push_back({id, format});
    return *this;
  }
  SessionDesc& parameter(std::string name, double value) {
    parameters.push_back({std::move(name), value});
    return *this;
  }
};

}  // namespace dn::client
