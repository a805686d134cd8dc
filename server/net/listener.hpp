// Listening sockets for tcp://HOST:PORT and unix:///PATH endpoints.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace dn::server::net {

struct Endpoint {
  enum class Kind { Tcp, Unix } kind = Kind::Tcp;
  std::string host;  // Tcp: numeric IPv4/IPv6 address or "localhost"
  uint16_t port = 0;
  std::string path;  // Unix
  std::string url;   // as given
};

// Parses a listen URL; on failure returns nullopt and sets `error` to a reason naming the URL.
std::optional<Endpoint> parse_endpoint(const std::string& url, std::string& error);

// True when the endpoint only accepts connections from this machine.
bool is_loopback(const Endpoint& endpoint);

struct Listener {
  Endpoint endpoint;
  int fd = -1;
  uint16_t bound_port = 0;  // the real port when 0 was asked for
  bool proxied = false;     // --listen-proxied: each connection starts with a PROXY v2 header
  // Unix: the socket file this process created (device, inode), so that
  // closing removes it and never a file another process put there since.
  uint64_t socket_dev = 0, socket_ino = 0;
};

// Creates a non-blocking listening socket; throws std::runtime_error naming the endpoint and errno.
// A Unix socket path where something answers (another server) is refused; a
// socket file nothing answers on (a crashed run's) is replaced.
// A Unix socket file is owner-only (0600) unless `other_users` is set, when it
// is 0666 and the server's peer-credential check alone decides who may talk.
Listener open_listener(const Endpoint& endpoint, bool other_users = false);
void close_listener(Listener& listener);

}  // namespace dn::server::net
