// ReconnectingSession: a Session plus what it takes to replace it after a
// lost connection. Invariant: pending_ holds exactly the frames session_ has
// in flight (session_->in_flight() == pending_.size()), so whatever session_
// hands out or loses can be named by frame index.
#include "dn/client/reconnecting_session.hpp"

#include <algorithm>
#include <thread>

namespace dn::client {

namespace {

using Clock = std::chrono::steady_clock;

// Worth another attempt: the server is not there (yet), or is there but
// cannot take the session right now. A refusal that will not change by
// waiting (a wrong token, an unknown pipeline, a bad channel) is thrown.
bool worth_retrying(const Error& e) {
  if (e.kind() == ErrorKind::Transport) return true;
  if (e.kind() != ErrorKind::Server) return false;
  using C = protocol::ErrorCode;
  switch (e.code()) {
    case C::ShuttingDown:
    case C::LimitExceeded:
    case C::NotReady:
    case C::Timeout:
    case C::DeviceError:
    case C::Internal: return true;
    default: return false;
  }
}

}  // namespace

ReconnectingSession::ReconnectingSession(std::string_view url, SessionDesc desc, ConnectOptions connect,
                                         ReconnectOptions reconnect)
    : ReconnectingSession(Connection::connect(url, connect), std::move(desc), connect, std::move(reconnect)) {}

ReconnectingSession::ReconnectingSession(Connection connection, SessionDesc desc, ConnectOptions connect,
                                         ReconnectOptions reconnect)
    : desc_(std::move(desc)), connect_(std::move(connect)), reconnect_(std::move(reconnect)) {
  servers_.urls.push_back(connection.endpoint());
  session_.emplace(connection.open_session(desc_));
  connection_.emplace(std::move(connection));
}

bool ReconnectingSession::connection_lost(const Error& e) const {
  return e.kind() != ErrorKind::Usage && connection_ && !connection_->is_open();
}

size_t ReconnectingSession::pop_answered(size_t in_flight_before) {
  const size_t now = session_ ? session_->in_flight() : 0;
  const size_t n = in_flight_before > now ? in_flight_before - now : 0;
  for (size_t i = 0; i < n && !pending_.empty(); ++i) pending_.pop_front();
  return n;
}

void ReconnectingSession::lose_connection(const Error& cause) {
  const std::string endpoint = connection_->endpoint();
  const uint64_t session_id = session_ ? session_->id() : 0;
  // Results (and per-frame errors) that arrived before the loss still go out, in order.
  while (session_ && session_->in_flight() > 0) {
    const size_t before = session_->in_flight();
    try {
      std::optional<Result> r = session_->poll();
      if (!r) break;
      pop_answered(before);
      delivered_.push_back({std::move(*r), std::nullopt});
    } catch (const Error& e) {
      if (pop_answered(before) == 0) break;  // the loss itself: nothing more will come
      delivered_.push_back({std::nullopt, e});
    }
  }
  // The rest will never be answered: one error each, never a silent drop.
  std::string why = cause.server_message();
  if (why.rfind("connection lost: ", 0) == 0) why.erase(0, 17);
  for (uint64_t index : pending_)
    delivered_.push_back(
        {std::nullopt,
         Error::transport(endpoint, "frame " + std::to_string(index) + " lost: " + why +
                                        " before its result arrived (session " + std::to_string(session_id) +
                                        "; the next frame opens a new session, history reset)")});
  frames_lost_ += pending_.size();
  lost_in_last_loss_ += pending_.size();
  pending_.clear();
  lost_session_id_ = session_id;
  loss_cause_ = cause.what();
  session_.reset();  // its destructor sends nothing on a broken connection
  connection_.reset();
  reset_next_ = true;
}

void ReconnectingSession::reconnect(uint64_t first_frame_index) {
  const auto start = Clock::now();
  Milliseconds delay = reconnect_.first_delay;
  for (unsigned attempt = 1;; ++attempt) {
    const std::string& url = servers_.pick();
    try {
      Connection c = Connection::connect(url, connect_);
      Session s = c.open_session(desc_);
      Reconnected event;
      event.endpoint = c.endpoint();
      event.old_session_id = lost_session_id_;
      event.new_session_id = s.id();
      event.first_frame_index = first_frame_index;
      event.frames_lost = lost_in_last_loss_;
      event.attempts = attempt;
      event.took = std::chrono::duration_cast<Milliseconds>(Clock::now() - start);
      event.cause = loss_cause_;
      session_.emplace(std::move(s));
      connection_.emplace(std::move(c));
      ++reconnections_;
      lost_in_last_loss_ = 0;
      if (reconnect_.on_reconnect) reconnect_.on_reconnect(event);
      return;
    } catch (const Error& e) {
      if (!worth_retrying(e)) throw;
      const auto waited = Clock::now() - start;
      if (waited + delay > reconnect_.give_up_after)
        throw Error::transport(url,
                               "could not reconnect within " + std::to_string(reconnect_.give_up_after.count()) +
                                   " ms (" + std::to_string(attempt) + " attempts) after losing session " +
                                   std::to_string(lost_session_id_) + " (" + loss_cause_ + "); last attempt: " +
                                   e.what(),
                               e.code());
      std::this_thread::sleep_for(delay);
      delay = std::min(delay * 2, reconnect_.max_delay);
    }
  }
}

uint64_t ReconnectingSession::submit(const FrameInput& frame) {
  if (closed_) throw Error::usage("ReconnectingSession is closed");
  const uint64_t index = frame.frame_index ? *frame.frame_index : (last_index_ ? *last_index_ + 1 : 0);
  // Checked here as well as by Session: a new session would accept any index.
  if (last_index_ && index <= *last_index_)
    throw Error::usage(protocol::ErrorCode::OutOfOrder, "FRAME.frame_index",
                       "frame index " + std::to_string(index) + " is not greater than the previous frame's " +
                           std::to_string(*last_index_));
  FrameInput f = frame;
  f.frame_index = index;
  for (int losses = 0;; ++losses) {
    if (!session_) reconnect(index);
    if (reset_next_) f.reset();
    try {
      session_->submit(f);
      pending_.push_back(index);
      last_index_ = index;
      reset_next_ = false;
      return index;
    } catch (const Error& e) {
      if (!connection_lost(e)) throw;
      lose_connection(e);
      // A server that refused this very frame before hanging up (its ERROR
      // beats the broken pipe) would refuse it again; so would one that
      // keeps dying under it.
      if (e.kind() == ErrorKind::Server || losses >= 2) throw;
    }
  }
}

Result ReconnectingSession::take_delivered() {
  Delivery d = std::move(delivered_.front());
  delivered_.pop_front();
  if (d.error) throw *d.error;
  return std::move(*d.result);
}

Result ReconnectingSession::wait() {
  if (!delivered_.empty()) return take_delivered();
  if (!session_ || pending_.empty()) throw Error::usage("ReconnectingSession::wait(): no frame in flight");
  const size_t before = session_->in_flight();
  try {
    Result r = session_->wait();
    pop_answered(before);
    return r;
  } catch (const Error& e) {
    if (pop_answered(before) > 0 || !connection_lost(e)) throw;  // that frame's own error
    lose_connection(e);
    return take_delivered();
  }
}

std::optional<Result> ReconnectingSession::poll() {
  if (!delivered_.empty()) return take_delivered();
  if (!session_ || pending_.empty()) return std::nullopt;
  const size_t before = session_->in_flight();
  try {
    std::optional<Result> r = session_->poll();
    pop_answered(before);
    return r;
  } catch (const Error& e) {
    if (pop_answered(before) > 0 || !connection_lost(e)) throw;
    lose_connection(e);
    return take_delivered();
  }
}

void ReconnectingSession::close() {
  closed_ = true;
  pending_.clear();
  delivered_.clear();
  if (session_ && connection_ && connection_->is_open()) {
    try {
      session_->close();
    } catch (const Error& e) {
      if (!connection_lost(e)) throw;
    }
  }
  session_.reset();
  connection_.reset();
}

}  // namespace dn::client
