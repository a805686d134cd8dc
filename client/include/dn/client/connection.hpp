// A connection to dnserver: connect + handshake, then sessions, watchers,
// ping and stats over one socket.
//
// Threading: a Connection and the Sessions/Watchers made from it share one
// socket and one receive queue; use them from one thread at a time. Use one
// Connection per thread (or per camera stream) for parallelism.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "dn/client/error.hpp"
#include "dn/client/options.hpp"
#include "dn/client/session_desc.hpp"
#include "dn/protocol/messages.hpp"

namespace dn::client {

namespace detail {
class ConnectionState;
}
class Session;
class Watcher;

class Connection {
 public:
  // Parses the URL (tcp://HOST:PORT or unix:///path), connects, sends HELLO
  // and waits for WELCOME. Throws Error: Usage for a bad URL, Transport when
  // the server cannot be reached, Server when it answers ERROR (e.g.
  // Unauthenticated).
  static Connection connect(std::string_view url, const ConnectOptions& options = {});

  Connection(Connection&&) noexcept;
  Connection& operator=(Connection&&) noexcept;
  ~Connection();

  // Server version, device, limits, pipelines; with a 1.1 server
  // (welcome().has_parameters) every pipeline's parameter table.
  const protocol::Welcome& welcome() const;
  const std::string& endpoint() const;  // canonical URL, as used in error messages
  // min(the server's minor version, this library's): 6 or more means sessions have watch keys.
  uint8_t protocol_minor() const;
  const protocol::PipelineInfo* find_pipeline(std::string_view name) const;  // from WELCOME; nullptr if absent

  // PING -> PONG round trip.
  std::chrono::duration<double, std::milli> ping();
  // STATS_REQUEST -> STATS.
  protocol::Stats stats();
  // OPEN_SESSION -> SESSION. When the server announced parameter tables
  // (protocol 1.1), the parameters are checked first (check_parameters in
  // parameters.hpp): an unknown name or a value out of range throws Usage /
  // InvalidParameter without sending anything. Server errors
  // (UnknownPipeline, MissingChannel, LimitExceeded, ...) are thrown as Error
  // with the server's code and field.
  Session open_session(const SessionDesc& desc);
  // ATTACH -> SESSION (read_only), then RESULTs through the Watcher.
  // `watch_key` is the session's key, as its owner got it (Session::watch_key(),
  // printed by `dn denoise` and `dnrender --server`): a server of protocol 1.6
  // or later refuses an ATTACH without it (Server error UnknownSession, the
  // same as for an id that does not exist). A key that is not 32 lowercase hex
  // digits throws Usage without sending anything. An older server takes no key.
  Watcher attach(uint64_t session_id, std::string_view watch_key);

  // Closes the socket. Sessions and Watchers of this connection throw
  // Transport errors afterwards. Also done by the destructor of the last owner.
  void close();
  bool is_open() const;

 private:
  explicit Connection(std::shared_ptr<detail::ConnectionState> state);
  std::shared_ptr<detail::ConnectionState> state_;
};

}  // namespace dn::client
