// Who is at the other end of an accepted connection, for per-peer limits:
// the Unix uid where the kernel can tell (a Unix socket's SO_PEERCRED; on
// loopback TCP the owner of the peer's socket in /proc/net/tcp{,6}), else the
// remote IP address. Two processes of different users on this machine are
// two peers even though both come from 127.0.0.1.
#pragma once

#include <sys/socket.h>

#include <string>

namespace dn::server::net {

// "uid:1000", "ip:192.0.2.7" or "ip:::1"; "unknown" when nothing is known.
std::string peer_identity(int fd, const sockaddr_storage& peer, bool is_unix);
// "ip:ADDRESS" of an IPv4/IPv6 address, "unknown" for anything else: the
// identity of an address alone (a balancer's forwarded client, whose socket
// and so whose uid this machine cannot see).
std::string address_identity(const sockaddr_storage& address);

}  // namespace dn::server::net
