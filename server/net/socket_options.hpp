// Socket helpers of the server's accept path: a printable peer address and
// the buffer/latency options every accepted connection gets.
#pragma once

#include <sys/socket.h>

#include <string>

namespace dn::server::net {

// "HOST:PORT" for TCP peers, "unix" for Unix-domain ones.
std::string peer_name(const sockaddr_storage& addr, bool is_unix);

// Large socket buffers (a 1280x720 frame in a few syscalls) and, on TCP, no
// Nagle delay and a dead-peer bound: keepalive probes from dead_peer_s / 2
// every dead_peer_s / 12 (6 of them), and TCP_USER_TIMEOUT dead_peer_s for
// data that is never acknowledged (0: the kernel's defaults, hours).
void tune_socket(int fd, bool is_unix, double dead_peer_s);

}  // namespace dn::server::net
