// One client connection: non-blocking reads through the protocol's framing
// state machine and a queue of outgoing messages written with partial writes.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "dn/protocol/codec.hpp"

namespace dn::server::net {

using Clock = std::chrono::steady_clock;
using Bytes = std::shared_ptr<const std::vector<uint8_t>>;

class Connection {
 public:
  enum class ReadStatus { Open, Closed, Failed };
  using MessageHandler = std::function<void(const protocol::Header&, std::vector<uint8_t>&& payload)>;

  Connection(int fd, uint64_t id, bool is_unix, std::string peer, uint64_t max_message_bytes);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  int fd() const { return fd_; }
  uint64_t id() const { return id_; }
  bool is_unix() const { return is_unix_; }
  const std::string& peer() const { return peer_; }

  // Reads until the socket would block, at most `budget` bytes, handing each
  // complete message to `handler`. Stops early once reading is paused.
  ReadStatus read_available(const MessageHandler& handler, size_t budget);
  const protocol::DecodeError& read_error() const { return reader_.error(); }
  // Largest message accepted from now on: bounds what one peer can make us allocate.
  void set_max_message_bytes(uint64_t bytes) { reader_.set_max_message_bytes(bytes); }

  // Queues an encoded message. A watch message (watch_session != 0) replaces
  // an older one of the same session that has not started going out, so a
  // watcher only ever receives the latest frame.
  void queue(Bytes bytes, uint64_t watch_session = 0);
  // Writes as much as the socket takes. Returns false on a write error.
  bool flush();
  bool has_pending_output() const { return !out_.empty(); }
  uint64_t queued_bytes() const { return queued_bytes_; }

  // Connection lifecycle flags, owned by the server.
  bool authenticated = false;
  // min(client's HELLO minor, ours), set with authenticated: what this
  // connection may carry (docs/protocol.md §10).
  uint8_t negotiated_minor = 0;
  // Presented the server's token (so one is configured): STATS shows it every
  // session, not only its own (docs/server.md, "Security").
  bool administrator = false;
  bool close_after_flush = false;  // a fatal error was queued; stop reading, close once flushed
  bool reading_paused = false;
  Clock::time_point created = Clock::now();
  Clock::time_point last_received = Clock::now();
  Clock::time_point last_ping_sent{};
  uint64_t bytes_in = 0;
  uint64_t bytes_out = 0;
  std::vector<uint64_t> owned_sessions;
  uint32_t sessions_being_built = 0;  // OPEN_SESSION accepted, pipeline still being built off the loop
  std::vector<uint64_t> watched_sessions;

 private:
  struct Outgoing {
    Bytes bytes;
    size_t offset = 0;
    uint64_t watch_session = 0;
  };
  int fd_;
  uint64_t id_;
  bool is_unix_;
  std::string peer_;
  protocol::MessageReader reader_;
  std::deque<Outgoing> out_;
  uint64_t queued_bytes_ = 0;
};

}  // namespace dn::server::net
