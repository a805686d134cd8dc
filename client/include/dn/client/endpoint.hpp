// Server addresses: "tcp://HOST:PORT" (HOST a name, an IPv4 address or a
// bracketed IPv6 address) and "unix:///absolute/path" (or "unix://relative/path").
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "dn/protocol/messages.hpp"

namespace dn::client {

// Where dnserver listens when started without --listen, and so where the dn
// tool connects when given neither --server nor $DN_SERVER.
inline constexpr const char* kDefaultServerUrl = protocol::kDefaultServerUrl;

struct Endpoint {
  enum class Kind { Tcp, Unix };
  Kind kind = Kind::Tcp;
  std::string host;  // Tcp: without brackets
  uint16_t port = 0;  // Tcp
  std::string path;  // Unix

  std::string to_string() const;  // canonical URL
};

// Throws dn::client::Error (kind Usage) with a message saying what was wrong
// and what is accepted.
Endpoint parse_endpoint(std::string_view url);

}  // namespace dn::client
