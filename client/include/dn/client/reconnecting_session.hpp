// A session that outlives its server connection (opt-in): when the
// connection is lost (the server crashed, was killed or restarted, the
// network dropped), the frames in flight are reported lost, one Error each,
// and the next submit() reconnects, with backoff for a bounded time, and
// opens a new session with the same SessionDesc. The new session starts
// with empty history: its first frame is sent with the reset flag.
//
//   client::ReconnectingSession s(url, desc);
//   for (;;) {
//     s.submit(frame);                       // reconnects first if the connection was lost
//     try { while (auto r = s.poll()) present(*r); }
//     catch (const client::Error& e) { ... } // a frame lost with the connection, or rejected
//   }
//
// Server errors for one frame (a rejected plane) are thrown by wait()/poll()
// as with Session and do not reconnect; only a lost connection does.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "dn/client/connection.hpp"
#include "dn/client/error.hpp"
#include "dn/client/options.hpp"
#include "dn/client/session.hpp"
#include "dn/client/session_desc.hpp"

namespace dn::client {

// What submit() tells on_reconnect after it reopened the session.
struct Reconnected {
  std::string endpoint;              // the server the new session is on
  uint64_t old_session_id = 0;       // the session lost with the connection
  uint64_t new_session_id = 0;       // its replacement (new history, new watch key)
  uint64_t first_frame_index = 0;    // the first frame sent to it, with the reset flag
  uint64_t frames_lost = 0;          // frames in flight at the loss; wait()/poll() throw one Error for each
  unsigned attempts = 0;             // connection attempts it took
  std::chrono::milliseconds took{0};  // from the first attempt to the new session
  std::string cause;                 // what() of the error that ended the old connection
};

struct ReconnectOptions {
  // How long one reconnection keeps trying before submit() gives up and
  // throws a Transport error naming the last attempt's failure (a later
  // submit() tries again).
  Milliseconds give_up_after{30000};
  // Wait before the second attempt; doubled after each failure up to max_delay.
  Milliseconds first_delay{100};
  Milliseconds max_delay{2000};
  // Called by submit() once the new session is open (e.g. to print a line).
  std::function<void(const Reconnected&)> on_reconnect;
};

class ReconnectingSession {
 public:
  // Connects to `url` and opens a session of `desc` (no retry for this first
  // open: an error here is thrown as by Connection::connect / open_session).
  ReconnectingSession(std::string_view url, SessionDesc desc, ConnectOptions connect = {},
                      ReconnectOptions reconnect = {});
  // Adopts a connection the caller made (e.g. to read WELCOME first) with
  // `connect`, the options used again for every reconnection.
  ReconnectingSession(Connection connection, SessionDesc desc, ConnectOptions connect = {},
                      ReconnectOptions reconnect = {});

  // Sends the frame and returns its index (default: one more than the last
  // frame's, across reconnections). If the connection was lost, reconnects
  // first; if the loss is found while sending, the frame is sent again on the
  // new session. Throws Transport when reconnecting gives up, Server when the
  // server refuses the new session (e.g. Unauthenticated, UnknownPipeline).
  uint64_t submit(const FrameInput& frame);
  // Next result in submission order (blocking) / if already arrived. A frame
  // lost with its connection throws Transport:
  //   "transport error on tcp://127.0.0.1:7878: frame 12 lost: the server closed the connection before its result
  //    arrived (session 81…; the next frame opens a new session, history reset)"
  // A frame the server rejected throws its Server error. Neither ends the session.
  Result wait();
  std::optional<Result> poll();
  // Frames submitted and not yet returned (results, errors or lost) by wait()/poll().
  size_t in_flight() const { return delivered_.size() + pending_.size(); }
  // Closes the current session; a session lost with its connection is gone already.
  void close();

  // The current connection and session (they change at each reconnection);
  // session() is nullptr between a loss and the next submit().
  Connection* connection() { return connection_ ? &*connection_ : nullptr; }
  Session* session() { return session_ ? &*session_ : nullptr; }
  uint64_t reconnections() const { return reconnections_; }
  uint64_t frames_lost() const { return frames_lost_; }

 private:
  struct Delivery {  // a frame's outcome waiting for wait()/poll(), ahead of the current session's
    std::optional<Result> result;
    std::optional<Error> error;
  };
  // Where reconnections go. One address today; a list (several backends,
  // tried in turn) needs only a constructor that fills it.
  struct Servers {
    std::vector<std::string> urls;
    size_t next = 0;
    const std::string& pick() { return urls[next++ % urls.size()]; }
  };

  bool connection_lost(const Error& e) const;
  size_t pop_answered(size_t in_flight_before);  // drops from pending_ what session_ handed out since
  void lose_connection(const Error& cause);      // salvages arrived results, marks the rest lost
  void reconnect(uint64_t first_frame_index);
  Result take_delivered();

  Servers servers_;
  SessionDesc desc_;
  ConnectOptions connect_;
  ReconnectOptions reconnect_;
  std::optional<Connection> connection_;
  std::optional<Session> session_;
  std::deque<uint64_t> pending_;       // frame indices in flight on session_, in order
  std::deque<Delivery> delivered_;     // outcomes to hand out before session_'s
  std::optional<uint64_t> last_index_;
  bool reset_next_ = false;            // the next frame starts a new session's history
  bool closed_ = false;
  uint64_t lost_session_id_ = 0;
  uint64_t lost_in_last_loss_ = 0;
  std::string loss_cause_;
  uint64_t reconnections_ = 0;
  uint64_t frames_lost_ = 0;
};

}  // namespace dn::client
