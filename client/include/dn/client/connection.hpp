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
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "dn/client/error.hpp"
#include "dn/protocol/messages.hpp"

namespace dn::client {

namespace detail {
class ConnectionState;
}
class Session;
class Watcher;

using Milliseconds = std::chrono::milliseconds;

struct ConnectOptions {
  std::string client_name = "dn-client";
  // The token sent in HELLO, in order of precedence: auth_token if set; the
  // first line of token_file if non-empty; $DN_TOKEN; the first line of the
  // file named by $DN_TOKEN_FILE; otherwise empty (a server without auth).
  std::optional<std::string> auth_token;
  std::string token_file;
  Milliseconds connect_timeout{10000};  // socket connect + HELLO/WELCOME
  Milliseconds io_timeout{120000};      // longest wait for one reply or one send to progress; 0 = forever
  uint64_t max_message_bytes = 0;       // largest message accepted from the server; 0 = 4 GiB
  int socket_buffer_bytes = 8 << 20;    // SO_SNDBUF / SO_RCVBUF request; 0 keeps the OS default
};

// The token ConnectOptions resolves to (see above). Throws Error (Usage) when
// a named token file cannot be read.
std::string resolve_auth_token(const ConnectOptions& options);

// What OPEN_SESSION asks for.
struct SessionDesc {
  uint32_t width = 0;
  uint32_t height = 0;
  std::string pipeline;
  protocol::Format output_format = protocol::Format::F32;
  std::vector<protocol::Parameter> parameters;
  std::vector<protocol::ChannelDecl> channels;
  // Frames a Session keeps in flight before submit() blocks. 0: the server's
  // WELCOME limits.max_frames_in_flight (3 when the server reports 0). Values
  // above the server's limit are clamped to it.
  uint32_t max_in_flight = 0;

  SessionDesc& channel(protocol::ChannelId id, protocol::Format format = protocol::Format::F32) {
    channels.push_back({id, format});
    return *this;
  }
  SessionDesc& parameter(std::string name, double value) {
    parameters.push_back({std::move(name), value});
    return *this;
  }
};

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

  const protocol::Welcome& welcome() const;
  const std::string& endpoint() const;  // canonical URL, as used in error messages
  const protocol::PipelineInfo* find_pipeline(std::string_view name) const;  // from WELCOME; nullptr if absent

  // PING -> PONG round trip.
  std::chrono::duration<double, std::milli> ping();
  // STATS_REQUEST -> STATS.
  protocol::Stats stats();
  // OPEN_SESSION -> SESSION. Server errors (UnknownPipeline, MissingChannel,
  // LimitExceeded, ...) are thrown as Error with the server's code and field.
  Session open_session(const SessionDesc& desc);
  // ATTACH -> SESSION (read_only), then RESULTs through the Watcher.
  Watcher attach(uint64_t session_id);

  // Closes the socket. Sessions and Watchers of this connection throw
  // Transport errors afterwards. Also done by the destructor of the last owner.
  void close();
  bool is_open() const;

 private:
  explicit Connection(std::shared_ptr<detail::ConnectionState> state);
  std::shared_ptr<detail::ConnectionState> state_;
};

}  // namespace dn::client
