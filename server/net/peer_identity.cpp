#include "server/net/peer_identity.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace dn::server::net {
namespace {

// /proc/net/tcp's form of an address: each 32-bit word of it as the kernel
// holds it, %08X, then ":" and the port %04X.
std::string proc_address(const sockaddr_storage& a) {
  char out[64] = "";
  if (a.ss_family == AF_INET) {
    auto* v4 = reinterpret_cast<const sockaddr_in*>(&a);
    std::snprintf(out, sizeof out, "%08X:%04X", v4->sin_addr.s_addr, ntohs(v4->sin_port));
  } else if (a.ss_family == AF_INET6) {
    auto* v6 = reinterpret_cast<const sockaddr_in6*>(&a);
    uint32_t w[4];
    static_assert(sizeof w == sizeof v6->sin6_addr);
    std::memcpy(w, &v6->sin6_addr, sizeof w);
    std::snprintf(out, sizeof out, "%08X%08X%08X%08X:%04X", w[0], w[1], w[2], w[3], ntohs(v6->sin6_port));
  }
  return out;
}

bool is_loopback(const sockaddr_storage& a) {
  if (a.ss_family == AF_INET)
    return (ntohl(reinterpret_cast<const sockaddr_in*>(&a)->sin_addr.s_addr) >> 24) == 127;
  if (a.ss_family == AF_INET6) {
    const in6_addr& v6 = reinterpret_cast<const sockaddr_in6*>(&a)->sin6_addr;
    if (IN6_IS_ADDR_LOOPBACK(&v6)) return true;
    return IN6_IS_ADDR_V4MAPPED(&v6) && v6.s6_addr[12] == 127;
  }
  return false;
}

// The uid owning the socket whose local end is `peer` and remote end `ours`
// (the peer process's socket, on this machine), from /proc/net/tcp{,6}.
bool loopback_peer_uid(const sockaddr_storage& peer, const sockaddr_storage& ours, unsigned& uid) {
  const std::string local = proc_address(peer), remote = proc_address(ours);
  for (const char* table : {"/proc/net/tcp", "/proc/net/tcp6"}) {
    std::ifstream in(table);
    std::string line;
    std::getline(in, line);  // column titles
    while (std::getline(in, line)) {
      std::istringstream f(line);
      std::string sl, l, r, state, queues, timer, retransmits;
      unsigned owner = 0;
      if (!(f >> sl >> l >> r >> state >> queues >> timer >> retransmits >> owner)) continue;
      if (l == local && r == remote) {
        uid = owner;
        return true;
      }
    }
  }
  return false;
}

}  // namespace

std::string peer_identity(int fd, const sockaddr_storage& peer, bool is_unix) {
  if (is_unix) {
    ucred cred{};
    socklen_t len = sizeof cred;
    if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &len) == 0) return "uid:" + std::to_string(cred.uid);
    return "unknown";
  }
  sockaddr_storage ours{};
  socklen_t len = sizeof ours;
  unsigned uid = 0;
  if (is_loopback(peer) && ::getsockname(fd, reinterpret_cast<sockaddr*>(&ours), &len) == 0 &&
      loopback_peer_uid(peer, ours, uid))
    return "uid:" + std::to_string(uid);
  return address_identity(peer);
}

std::string address_identity(const sockaddr_storage& peer) {
  char host[INET6_ADDRSTRLEN] = "";
  if (peer.ss_family == AF_INET)
    inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(&peer)->sin_addr, host, sizeof host);
  else if (peer.ss_family == AF_INET6)
    inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(&peer)->sin6_addr, host, sizeof host);
  else
    return "unknown";
  return std::string("ip:") + host;
}

}  // namespace dn::server::net
