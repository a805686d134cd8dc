// Internal: the queues of messages for Watchers (ATTACH streams), keyed by
// the ATTACH request id. Not installed.
#pragma once

#include <cstdint>
#include <deque>
#include <unordered_map>

#include "incoming.hpp"

namespace dn::client::detail {

// Messages for a watcher: RESULT copies, or the end of the stream.
struct WatchQueue {
  uint64_t session_id = 0;
  std::deque<Incoming> items;
};

class WatchQueues {
 public:
  void add(uint64_t attach_request_id, uint64_t session_id);
  void remove(uint64_t attach_request_id);
  WatchQueue* find(uint64_t attach_request_id);

  // Moves `in` into a watcher's queue and returns true when it belongs to
  // one: its request id is an ATTACH's, or it is a RESULT or SESSION_CLOSED
  // of a watched session that the server sent with another id.
  bool route(Incoming& in);

 private:
  std::unordered_map<uint64_t, WatchQueue> queues_;
};

}  // namespace dn::client::detail
