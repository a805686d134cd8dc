// Internal: one message received from the server, as the connection's
// reader hands it to the demultiplexer. Not installed.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include "dn/protocol/messages.hpp"

namespace dn::client::detail {

using Clock = std::chrono::steady_clock;

// One decoded message. Plane views inside `message` point into *payload.
struct Incoming {
  protocol::Header header{};
  std::shared_ptr<std::vector<uint8_t>> payload;
  protocol::Message message;
  Clock::time_point received{};
};

}  // namespace dn::client::detail
