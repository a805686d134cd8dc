// Socket helpers of the server's accept path: a printable peer address and
// the buffer/latency options every accepted connection gets.
#pragma once

#include <sys/socket.h>

#include <string>

namespace dn::server::net {

// "HOST:PORT" for TCP peers, "unix" for Unix-domain ones.
std::string peer_name(const sockaddr_storage& addr, bool is_unix);

// Large socket buffers (a 1280x720 frame in a few syscalls) and, on TCP, no Nagle delay.
void tune_socket(int fd, bool is_unix);

}  // namespace dn::server::net
