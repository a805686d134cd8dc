// The server's connection layer: listeners, admission (connection limits,
// per-peer limits, Unix peer credentials, PROXY v2 headers), framing, HELLO
// and its token, replies, timeouts and the heartbeat. Every other request of
// an authenticated connection goes to the RequestHandler above it (the
// session service). Runs on the event loop.
#pragma once

#include <sys/socket.h>

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "dn/protocol/codec.hpp"
#include "server/net/connection.hpp"
#include "server/net/event_loop.hpp"
#include "server/net/listener.hpp"
#include "server/options.hpp"
#include "server/stats.hpp"

namespace dn::server {

// What the connection layer asks of the layer above it.
class RequestHandler {
 public:
  virtual ~RequestHandler() = default;
  // A decoded request of an authenticated connection, other than HELLO, PING and PONG.
  virtual void on_request(net::Connection& c, const protocol::Header& h, protocol::Message&& m,
                          std::vector<uint8_t>&& payload) = 0;
  // The connection still waits for its sessions' builds or frames.
  virtual bool has_work(const net::Connection& c) const = 0;
  // Some session of the connection has its whole window of frames queued or on the device.
  virtual bool window_full(const net::Connection& c) const = 0;
  // The connection is gone: its sessions close and its watches end.
  virtual void on_closed(net::Connection& c) = 0;
};

class ConnectionLayer {
 public:
  using Bytes = net::Bytes;

  // Opens the listeners; throws std::runtime_error with a reason on bad options.
  ConnectionLayer(const ServerOptions& options, net::EventLoop& loop, ServerCounters& counters,
                  std::string device_name);
  ~ConnectionLayer();
  void set_handler(RequestHandler* handler) { handler_ = handler; }

  // Actual listening addresses (a port of 0 resolved).
  std::vector<std::string> listening_urls() const;
  // Serves a connected stream socket (made non-blocking) as if a Unix listener
  // had accepted it; returns its id.
  uint64_t adopt(int fd);
  // Shutdown: the listeners close and HELLO is refused from now on.
  void begin_shutdown();
  void close_all(const char* reason);
  // Output deadlines, message and handshake timeouts, idle timeout and heartbeat.
  void check_timers(std::chrono::steady_clock::time_point now);

  size_t size() const { return connections_.size(); }
  bool output_pending() const;
  net::Connection* find(uint64_t id);
  // STATS: the open connections and their byte counts.
  void add_live_state(LiveState& live) const;

  void send(net::Connection& c, const protocol::Message& m, uint64_t request_id);
  void send_encoded(net::Connection& c, Bytes bytes);
  // A frame for a watcher: replaces its older frame of that session not yet going out.
  void send_watched(net::Connection& c, Bytes bytes, uint64_t session_id);
  // fatal: the connection closes once the ERROR is written.
  void send_error(net::Connection& c, uint64_t request_id, protocol::ErrorCode code, std::string field,
                  std::string message, bool fatal);
  // Reading on or off (backpressure) and writing when output waits.
  void update_interest(net::Connection& c);
  // The largest frame the connection's sessions take (0: none) bounds the messages it may send.
  void set_largest_frame(net::Connection& c, uint64_t frame_bytes);

 private:
  void accept_from(net::Listener& listener);
  void admit(int fd, const sockaddr_storage& addr, bool is_unix, bool proxied = false);
  // --max-connections-per-peer, once the connection's peer is known and counted: a reason, or empty.
  std::string per_peer_refusal(const net::Connection& c) const;
  void refuse(net::Connection& c, const std::string& refusal);
  void on_proxy_header(net::Connection& c);
  void refuse_proxy_header(net::Connection& c, protocol::ErrorCode code, const std::string& reason);
  void on_event(uint64_t connection_id, uint32_t events);
  void on_message(net::Connection& c, const protocol::Header& header, std::vector<uint8_t>&& payload);
  void on_hello(net::Connection& c, const protocol::Header& h, const protocol::Hello& m);
  void close(uint64_t connection_id, const char* reason);
  void count_peer(const net::Connection& c, int delta);
  bool has_work(const net::Connection& c) const;

  const ServerOptions& options_;
  net::EventLoop& loop_;
  ServerCounters& counters_;
  std::string device_name_;
  RequestHandler* handler_ = nullptr;
  std::vector<net::Listener> listeners_;
  net::ReceiveBudget receive_budget_;  // --receive-budget, shared by every connection
  std::map<uint64_t, std::unique_ptr<net::Connection>> connections_;
  uint64_t next_id_ = 1;
  // Per-peer limits: open connections per peer identity, and those not through HELLO yet in all.
  std::map<std::string, uint32_t> peer_connections_;
  uint32_t unauthenticated_ = 0;
  bool shutting_down_ = false;
  std::map<uint8_t, Bytes> welcome_by_minor_;  // encoded WELCOME (request id 0) per negotiated minor
};

}  // namespace dn::server
