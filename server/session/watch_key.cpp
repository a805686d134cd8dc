#include "server/session/watch_key.hpp"

#include <sys/random.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "dn/protocol/messages.hpp"
#include "server/net/auth.hpp"

namespace dn::server {

std::string new_watch_key() {
  uint8_t bytes[protocol::kWatchKeyLength / 2];
  size_t filled = 0;
  while (filled < sizeof bytes) {
    const ssize_t n = ::getrandom(bytes + filled, sizeof bytes - filled, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw std::runtime_error(std::string("getrandom: ") + std::strerror(errno));
    filled += static_cast<size_t>(n);
  }
  static constexpr char kHex[] = "0123456789abcdef";
  std::string key;
  for (uint8_t b : bytes) {
    key += kHex[b >> 4];
    key += kHex[b & 15];
  }
  return key;
}

bool watch_key_matches(const std::string& expected, std::string_view presented) {
  // An empty key is refused without comparing: it says nothing about the session.
  return !presented.empty() && net::tokens_equal(expected, presented);
}

}  // namespace dn::server
