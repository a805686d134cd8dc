// PROXY protocol v2 headers for tests, written byte by byte from haproxy's
// doc/proxy-protocol.txt, section 2.2 (independent of server/net/proxy_header.cpp).
#pragma once

#include <cstdint>
#include <vector>

namespace dn::test {

inline const std::vector<uint8_t> kProxyV2Signature = {0x0D, 0x0A, 0x0D, 0x0A, 0x00, 0x0D,
                                                       0x0A, 0x51, 0x55, 0x49, 0x54, 0x0A};

// Signature, ver_cmd, family/transport byte, big-endian length (of `rest`
// unless given), then `rest`.
inline std::vector<uint8_t> proxy_v2(uint8_t ver_cmd, uint8_t family, const std::vector<uint8_t>& rest,
                                     int length = -1) {
  std::vector<uint8_t> h = kProxyV2Signature;
  const size_t n = length < 0 ? rest.size() : static_cast<size_t>(length);
  h.insert(h.end(), {ver_cmd, family, static_cast<uint8_t>(n >> 8), static_cast<uint8_t>(n & 0xFF)});
  h.insert(h.end(), rest.begin(), rest.end());
  return h;
}

// The IPv4 address block: source, destination, source port, destination port.
inline std::vector<uint8_t> ipv4_block(std::vector<uint8_t> source, uint16_t source_port,
                                       const std::vector<uint8_t>& destination, uint16_t destination_port) {
  source.insert(source.end(), destination.begin(), destination.end());
  source.insert(source.end(), {static_cast<uint8_t>(source_port >> 8), static_cast<uint8_t>(source_port & 0xFF),
                               static_cast<uint8_t>(destination_port >> 8),
                               static_cast<uint8_t>(destination_port & 0xFF)});
  return source;
}

// What HAProxy's send-proxy-v2 sends for a TCP/IPv4 client (PROXY, 0x11),
// and its check-send-proxy for a health check (LOCAL, UNSPEC, no address).
inline std::vector<uint8_t> proxy_v2_ipv4(const std::vector<uint8_t>& source, uint16_t source_port) {
  return proxy_v2(0x21, 0x11, ipv4_block(source, source_port, {192, 0, 2, 1}, 7001));
}
inline std::vector<uint8_t> proxy_v2_local() { return proxy_v2(0x20, 0x00, {}); }

}  // namespace dn::test
