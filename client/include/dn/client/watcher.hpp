// A read-only view of another client's session (ATTACH): the server streams
// RESULT copies; a watcher only cares about the newest one.
#pragma once

#include <chrono>
#include <deque>
#include <memory>
#include <optional>

#include "dn/client/session.hpp"
#include "dn/protocol/messages.hpp"

namespace dn::client {

class Watcher {
 public:
  Watcher(Watcher&&) noexcept;
  Watcher& operator=(Watcher&&) noexcept;
  ~Watcher();

  const protocol::Session& info() const { return info_; }  // SESSION reply (read_only = true)
  uint64_t session_id() const { return info_.session_id; }

  // Blocks until at least one RESULT has arrived (up to the connection's
  // io_timeout), then returns the newest, dropping older ones. Throws Error
  // when the session ends (Server error UnknownSession or the server's ERROR)
  // or the connection fails.
  Result next();
  // Same with an explicit timeout; nullopt when nothing arrived in time.
  std::optional<Result> next_for(std::chrono::milliseconds timeout);
  // Newest arrived RESULT, if any; never blocks.
  std::optional<Result> try_next();

  // Frames the server sent that next() skipped because a newer one had arrived.
  uint64_t dropped() const { return dropped_; }

  // The SESSION_CLOSED that ended the stream (its owner closed the session or
  // went away), once next() has thrown for it; nullopt while the stream runs
  // and when it ended otherwise (an ERROR, the connection failing).
  const std::optional<protocol::SessionClosed>& closed() const { return closed_; }

 private:
  friend class Connection;
  Watcher(std::shared_ptr<detail::ConnectionState> state, protocol::Session info, uint64_t attach_request_id);
  std::optional<Result> take_newest(bool throw_end);

  std::shared_ptr<detail::ConnectionState> state_;
  protocol::Session info_;
  uint64_t attach_request_id_ = 0;
  uint64_t dropped_ = 0;
  std::optional<protocol::SessionClosed> closed_;
};

}  // namespace dn::client
