#include "dn/client/watcher.hpp"

#include "connection_state.hpp"
#include "result_from_message.hpp"

namespace dn::client {

Watcher::Watcher(std::shared_ptr<detail::ConnectionState> state, protocol::Session info, uint64_t attach_request_id)
    : state_(std::move(state)), info_(std::move(info)), attach_request_id_(attach_request_id) {}

Watcher::Watcher(Watcher&& o) noexcept
    : state_(std::move(o.state_)),
      info_(std::move(o.info_)),
      attach_request_id_(o.attach_request_id_),
      dropped_(o.dropped_),
      closed_(std::move(o.closed_)) {}

Watcher& Watcher::operator=(Watcher&& o) noexcept {
  if (this != &o) {
    if (state_) state_->remove_watch(attach_request_id_);
    state_ = std::move(o.state_);
    info_ = std::move(o.info_);
    attach_request_id_ = o.attach_request_id_;
    dropped_ = o.dropped_;
    closed_ = std::move(o.closed_);
  }
  return *this;
}

Watcher::~Watcher() {
  // The server keeps streaming until the session ends or the connection
  // closes; later RESULTs for this session are dropped on arrival.
  if (state_) state_->remove_watch(attach_request_id_);
}

std::optional<Result> Watcher::take_newest(bool throw_end) {
  detail::WatchQueue* q = state_->watch(attach_request_id_);
  if (!q || q->items.empty()) return std::nullopt;
  // Newest RESULT wins. An ERROR or SESSION_CLOSED ends the stream: it is
  // thrown once the RESULTs before it have been handed out.
  std::optional<detail::Incoming> newest;
  while (!q->items.empty()) {
    detail::Incoming& front = q->items.front();
    const bool is_error = std::holds_alternative<protocol::Error>(front.message);
    const bool is_closed = std::holds_alternative<protocol::SessionClosed>(front.message);
    if (is_error || is_closed) {
      if (newest || !throw_end) break;
      if (is_error) throw Error::server(std::get<protocol::Error>(front.message), state_->endpoint());
      const auto& c = std::get<protocol::SessionClosed>(front.message);
      closed_ = c;
      throw Error::server({protocol::ErrorCode::UnknownSession, "ATTACH.session_id",
                           "session " + std::to_string(c.session_id) + " was closed after " +
                               std::to_string(c.frames_processed) + " frames"},
                          state_->endpoint());
    }
    detail::Incoming in = std::move(front);
    q->items.pop_front();
    if (!std::holds_alternative<protocol::Result>(in.message)) continue;
    if (newest) ++dropped_;
    newest = std::move(in);
  }
  if (!newest) return std::nullopt;
  return detail::result_from_message(std::move(*newest), info_, state_->endpoint());
}

std::optional<Result> Watcher::try_next() {
  if (!state_) throw Error::usage("watcher was moved from");
  if (auto r = take_newest(true)) return r;
  state_->pump_nonblocking();
  return take_newest(true);
}

std::optional<Result> Watcher::next_for(std::chrono::milliseconds timeout) {
  if (!state_) throw Error::usage("watcher was moved from");
  const auto deadline = detail::Clock::now() + timeout;
  for (;;) {
    if (auto r = take_newest(true)) {
      // Anything newer already in the socket buffer? (A failure is reported by the next call.)
      try {
        state_->pump_nonblocking();
      } catch (const Error&) {
        return r;
      }
      if (auto newer = take_newest(false)) {
        ++dropped_;
        return newer;
      }
      return r;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - detail::Clock::now());
    if (left.count() <= 0) return take_newest(true);
    try {
      state_->pump(left);
    } catch (const Error&) {
      // What arrived before the failure (results, the end of the session) comes first.
      if (auto* q = state_->watch(attach_request_id_); q && !q->items.empty()) continue;
      throw;
    }
  }
}

Result Watcher::next() {
  const auto t = state_ ? state_->io_timeout() : std::chrono::milliseconds(0);
  std::optional<Result> r;
  if (t.count() > 0) {
    r = next_for(t);
    if (!r)
      throw Error::transport(state_->endpoint(),
                             "timed out after " + std::to_string(t.count()) + " ms waiting for a RESULT of session " +
                                 std::to_string(info_.session_id),
                             protocol::ErrorCode::Timeout);
  } else {
    while (!r) r = next_for(std::chrono::hours(24));
  }
  return std::move(*r);
}

}  // namespace dn::client
