#include "server/net/auth.hpp"

#include <sys/socket.h>
#include <unistd.h>

namespace dn::server::net {

bool tokens_equal(std::string_view expected, std::string_view presented) {
  // Walk the expected token in full whatever was presented; fold the length difference in.
  size_t diff = expected.size() ^ presented.size();
  for (size_t i = 0; i < expected.size(); ++i) {
    unsigned char p = i < presented.size() ? static_cast<unsigned char>(presented[i]) : 0;
    diff |= static_cast<unsigned char>(expected[i]) ^ p;
  }
  return diff == 0;
}

bool unix_peer_allowed(int fd, const std::vector<uint32_t>& allowed, uint32_t& peer_uid) {
  ucred cred{};
  socklen_t len = sizeof cred;
  if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &len) != 0) return false;
  peer_uid = cred.uid;
  if (cred.uid == 0 || cred.uid == ::geteuid()) return true;
  for (uint32_t uid : allowed)
    if (uid == cred.uid) return true;
  return false;
}

}  // namespace dn::server::net
