// The PROXY protocol v2 header a balancer (HAProxy `send-proxy-v2`) puts in
// front of every connection it forwards, carrying the client's address
// (haproxy's doc/proxy-protocol.txt, section 2.2). Only listeners configured
// with --listen-proxied read it; there it must come first. Version 1 (text)
// is not accepted.
#pragma once

#include <sys/socket.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace dn::server::net {

// The fixed part: 12-byte signature, ver_cmd, family/transport, u16 length.
inline constexpr size_t kProxyFixedBytes = 16;
// Whole header, TLVs included: the spec's "smallest TCP segment any host
// must support" (576 - 40), which both versions are designed to fit in.
inline constexpr size_t kProxyMaxBytes = 536;

struct ProxyHeader {
  // LOCAL: the balancer's own connection (a health check); PROXY: relayed.
  enum class Command { Local, Proxy } command = Command::Local;
  // Set only for PROXY over TCP/IPv4 or TCP/IPv6: the client's address and
  // port (AF_INET/AF_INET6). Otherwise ss_family is AF_UNSPEC: keep the
  // socket's own peer (LOCAL, UNSPEC, UNIX, UDP: spec 2.2's fallback).
  sockaddr_storage source{};
  sockaddr_storage destination{};
  size_t size = 0;  // bytes the header took, TLVs included
};

struct ProxyParse {
  enum class Status { Complete, NeedMore, Error } status = Status::NeedMore;
  // NeedMore: the total number of bytes needed before parsing can go on
  // (never more than kProxyMaxBytes), so a reader takes exactly the header
  // and not one byte of what follows it.
  size_t need = kProxyFixedBytes;
  ProxyHeader header;  // Complete
  std::string error;   // Error: what was wrong, for the log
};

// Parses the header at the start of `bytes` (all bytes received so far). A
// wrong prefix is an error as soon as its first wrong byte is there.
ProxyParse parse_proxy_header(std::span<const uint8_t> bytes);

}  // namespace dn::server::net
