// Internal: where each received message goes — the reply a request waits
// for, a watcher's queue, or nowhere (remembering an ERROR nobody asked
// for). No sockets here. Not installed.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>

#include "incoming.hpp"
#include "watch_queues.hpp"

namespace dn::client::detail {

class Demultiplexer {
 public:
  // A reply to request_id (a message of type `sent`) is awaited.
  void expect(uint64_t request_id, protocol::MessageType sent);
  bool awaiting(uint64_t request_id) const;
  bool reply_ready(uint64_t request_id) const;
  // The reply if it has arrived (nullptr otherwise); it stays awaited.
  const Incoming* peek(uint64_t request_id) const;
  // Removes and returns the reply if it has arrived; otherwise it stays awaited.
  std::optional<Incoming> take(uint64_t request_id);
  // The reply will never be collected: drop it when (or if) it arrives.
  void forget(uint64_t request_id);
  // "OPEN_SESSION (request 4)", for timeout messages.
  std::string waiting_for(uint64_t request_id) const;

  void route(Incoming&& in);

  WatchQueues& watches() { return watches_; }
  // The last ERROR that answered nothing awaited (request_id 0, or a
  // forgotten request): a following hang-up can say why.
  const std::optional<protocol::Error>& last_unsolicited_error() const { return last_unsolicited_error_; }

 private:
  // request_id -> reply (empty until it arrives). Keys present = awaited.
  struct Pending {
    protocol::MessageType sent = protocol::MessageType::Ping;
    std::optional<Incoming> reply;
  };
  std::unordered_map<uint64_t, Pending> pending_;
  WatchQueues watches_;
  std::optional<protocol::Error> last_unsolicited_error_;
};

}  // namespace dn::client::detail
