// How a Connection connects: client name, token, timeouts, buffer sizes.
// Separate from connection.hpp so the library's internals can use it
// without depending on the Connection class.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

namespace dn::client {

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

}  // namespace dn::client
