// Internal: the socket, the framing reader and the receive demultiplexer
// shared by a Connection and its Sessions and Watchers. Not installed.
//
// The members are defined by job: connection_state.cpp (lifetime and
// failures), connect.cpp (socket connect + HELLO/WELCOME), send.cpp,
// receive.cpp (reading, waiting for replies), heartbeat.cpp (answering the
// server's PING); routing is demux.cpp and watch_queues.cpp.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "demux.hpp"
#include "dn/client/endpoint.hpp"
#include "dn/client/error.hpp"
#include "dn/client/options.hpp"
#include "dn/protocol/codec.hpp"
#include "incoming.hpp"
#include "watch_queues.hpp"

namespace dn::client::detail {

class ConnectionState {
 public:
  ConnectionState(Endpoint endpoint, const ConnectOptions& options);
  ~ConnectionState();
  ConnectionState(const ConnectionState&) = delete;
  ConnectionState& operator=(const ConnectionState&) = delete;

  // Socket connect (within connect_timeout) and HELLO/WELCOME.
  void open(const std::string& client_name, const std::string& token);

  const std::string& endpoint() const { return endpoint_str_; }
  const protocol::Welcome& welcome() const { return welcome_; }
  // min(server's WELCOME minor, ours): what this connection may carry (docs/protocol.md §10).
  uint8_t negotiated_minor() const { return negotiated_minor_; }
  Milliseconds io_timeout() const { return io_timeout_; }
  bool is_open() const { return fd_ >= 0 && !broken_; }
  void close();

  uint64_t next_request_id() { return next_request_id_++; }

  // Encodes and sends one message, registering `request_id` as awaiting a
  // reply when expect_reply. While the socket is not writable, arriving
  // messages are read and queued, so a server that is itself blocked sending
  // results can never deadlock us.
  // max_bytes (0: none) is the server's limit from WELCOME: a larger message
  // throws Usage/LimitExceeded without sending anything.
  void send(const protocol::Message& message, uint64_t request_id, uint32_t flags, bool expect_reply,
            uint64_t max_bytes = 0);

  // Blocks until the reply to request_id has arrived (deadline: io_timeout,
  // or `timeout` when given), removes and returns it.
  Incoming wait_reply(uint64_t request_id, std::optional<Milliseconds> timeout = std::nullopt);
  // Reply to request_id if it has arrived (after reading what is available).
  std::optional<Incoming> take_reply_if_ready(uint64_t request_id);
  bool reply_ready(uint64_t request_id) const { return demux_.reply_ready(request_id); }
  // The reply will never be collected: drop it when (or if) it arrives.
  void forget(uint64_t request_id) { demux_.forget(request_id); }

  // Watchers: messages with request_id == attach_request_id, and RESULTs of
  // session_id that answer no pending request, go to the watch queue.
  void add_watch(uint64_t attach_request_id, uint64_t session_id) { demux_.watches().add(attach_request_id, session_id); }
  void remove_watch(uint64_t attach_request_id) { demux_.watches().remove(attach_request_id); }
  WatchQueue* watch(uint64_t attach_request_id) { return demux_.watches().find(attach_request_id); }
  // Reads what is available without blocking and returns true if that was a
  // message; else waits up to `timeout` for something to read (nullopt:
  // io_timeout) and reads it. Returns false on timeout.
  bool pump(std::optional<Milliseconds> timeout);
  void pump_nonblocking();

  // Throws the connection's failure (Transport/Protocol) if it is broken.
  void check_usable() const;

 private:
  void connect_socket(Clock::time_point deadline, int buffer_bytes);
  void read_available();  // non-blocking: recv until EAGAIN, dispatching every complete message
  void dispatch(Incoming&& in);
  // The server's heartbeat PING (request_id 0) is answered here and goes no further.
  bool take_heartbeat(const Incoming& in);
  // Answers the server's heartbeat PING; never in the middle of another message.
  void send_pong_if_due();
  void wait_fd(short events, Clock::time_point deadline, bool has_deadline, const char* what);
  // mark_*: record the failure and close the socket; fail_*: and throw it.
  void mark_failed(Error e);
  Error transport_error(const std::string& message, protocol::ErrorCode code) const;
  [[noreturn]] void fail_transport(const std::string& message, protocol::ErrorCode code = protocol::ErrorCode::Internal);
  [[noreturn]] void fail_protocol(const protocol::DecodeError& e);
  [[noreturn]] void throw_send_failure(uint64_t request_id, bool expect_reply);
  Clock::time_point deadline_from(std::optional<Milliseconds> timeout, bool& has_deadline) const;

  Endpoint endpoint_;
  std::string endpoint_str_;
  int fd_ = -1;
  Milliseconds connect_timeout_;
  Milliseconds io_timeout_;
  int buffer_bytes_;
  uint64_t max_message_bytes_;
  protocol::MessageReader reader_;
  protocol::Welcome welcome_;
  uint8_t negotiated_minor_ = 0;
  uint64_t next_request_id_ = 1;
  std::vector<std::span<const uint8_t>> send_segments_;  // the message being sent, see send()
  std::optional<uint64_t> pong_due_;  // payload of a heartbeat PING not yet answered
  bool sending_ = false;              // a message is partly written: nothing else may be

  Demultiplexer demux_;
  uint64_t messages_dispatched_ = 0;  // lets pump() see that a read brought something

  bool broken_ = false;
  std::optional<Error> failure_;
  std::vector<uint8_t> send_buffer_;
};

}  // namespace dn::client::detail
