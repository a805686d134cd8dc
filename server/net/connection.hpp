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
#include "server/net/proxy_header.hpp"

namespace dn::server::net {

using Clock = std::chrono::steady_clock;
using Bytes = std::shared_ptr<const std::vector<uint8_t>>;

// Declared sizes of the large messages all connections are receiving at
// once (--receive-budget): one bound on what headers can make the server
// commit to, whatever the number of peers.
struct ReceiveBudget {
  uint64_t limit = 0;
  uint64_t in_use = 0;
};

class Connection {
 public:
  enum class ReadStatus { Open, Closed, Failed };
  // A complete message; refused: its payload was beyond the receive budget and dropped (empty).
  using MessageHandler =
      std::function<void(const protocol::Header&, std::vector<uint8_t>&& payload, bool refused)>;

  // Payloads above kBudgetedBytes take their declared size from `budget`
  // (may be null: no budget) while they are being received.
  static constexpr uint64_t kBudgetedBytes = 64u << 10;
  Connection(int fd, uint64_t id, bool is_unix, std::string peer, uint64_t max_message_bytes,
             ReceiveBudget* budget = nullptr);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  int fd() const { return fd_; }
  uint64_t id() const { return id_; }
  bool is_unix() const { return is_unix_; }
  const std::string& peer() const { return peer_; }
  // The client a balancer's PROXY header names replaces the socket's peer.
  void set_peer(std::string peer) { peer_ = std::move(peer); }

  // Proxied listeners (--listen-proxied): a PROXY v2 header comes before the
  // protocol. read_proxy_header() reads exactly its bytes, never the protocol's:
  // Open while it is incomplete (or once it is: awaiting_proxy_header() turns
  // false and proxy_header() holds it), Closed, or Failed (proxy_error()).
  void expect_proxy_header() { proxy_pending_ = true; }
  bool awaiting_proxy_header() const { return proxy_pending_; }
  ReadStatus read_proxy_header();
  const ProxyHeader& proxy_header() const { return proxy_.header; }
  const std::string& proxy_error() const { return proxy_.error; }

  // Reads until the socket would block, at most `budget` bytes, handing each
  // complete message to `handler`. Stops early once reading is paused.
  ReadStatus read_available(const MessageHandler& handler, size_t budget);
  const protocol::DecodeError& read_error() const { return reader_.error(); }
  // Largest message accepted from now on: bounds what one peer can make us allocate.
  void set_max_message_bytes(uint64_t bytes) { reader_.set_max_message_bytes(bytes); }
  // A message is partly received: since when, how much of it, of how much (0: header not complete).
  bool receiving() const { return reader_.bytes_buffered() > 0; }
  Clock::time_point message_started() const { return message_started_; }
  uint64_t message_bytes_received() const { return reader_.bytes_buffered(); }
  uint64_t message_bytes_declared() const { return reader_.bytes_declared(); }

  // Queues an encoded message. A watch message (watch_session != 0) replaces
  // an older one of the same session that has not started going out, so a
  // watcher only ever receives the latest frame.
  void queue(Bytes bytes, uint64_t watch_session = 0);
  // Writes as much as the socket takes. Returns false on a write error.
  bool flush();
  bool has_pending_output() const { return !out_.empty(); }
  uint64_t queued_bytes() const { return queued_bytes_; }
  // Last time queued output went out (or was queued onto an empty queue).
  Clock::time_point last_write_progress() const { return last_write_progress_; }

  // Connection lifecycle flags, owned by the server.
  std::string peer_identity;  // net::peer_identity(): what per-peer limits count
  bool authenticated = false;
  // min(client's HELLO minor, ours), set with authenticated: what this
  // connection may carry (docs/protocol.md §10).
  uint8_t negotiated_minor = 0;
  // Presented the server's token (so one is configured): STATS shows it every
  // session, not only its own (docs/server.md, "Security").
  bool administrator = false;
  bool close_after_flush = false;  // a fatal error was queued; stop reading, close once flushed
  // Backpressure: the server stops reading this connection. Time paused does
  // not count against the message in progress (its deadline moves on).
  bool reading_paused() const { return reading_paused_; }
  void set_reading_paused(bool paused);
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
  void release_budget();
  bool proxy_pending_ = false;
  std::vector<uint8_t> proxy_bytes_;  // the header so far
  ProxyParse proxy_;

  protocol::MessageReader reader_;
  ReceiveBudget* budget_;
  uint64_t budget_held_ = 0;  // this connection's share of budget_->in_use
  Clock::time_point message_started_{};
  bool reading_paused_ = false;
  Clock::time_point paused_since_{};
  std::deque<Outgoing> out_;
  uint64_t queued_bytes_ = 0;
  Clock::time_point last_write_progress_ = Clock::now();
};

}  // namespace dn::server::net
