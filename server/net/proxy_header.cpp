#include "server/net/proxy_header.hpp"

#include <netinet/in.h>

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace dn::server::net {
namespace {

constexpr uint8_t kSignature[12] = {0x0D, 0x0A, 0x0D, 0x0A, 0x00, 0x0D, 0x0A, 0x51, 0x55, 0x49, 0x54, 0x0A};

ProxyParse error(std::string reason) {
  ProxyParse p;
  p.status = ProxyParse::Status::Error;
  p.error = std::move(reason);
  return p;
}

std::string hex(uint8_t byte) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02X", byte);
  return text;
}

uint16_t be16(const uint8_t* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }

// Address block of TCP over IPv4 (0x11) or IPv6 (0x21): src, dst, src port, dst port.
void read_addresses(uint8_t family, const uint8_t* block, ProxyHeader& h) {
  if (family == 0x1) {
    auto* src = reinterpret_cast<sockaddr_in*>(&h.source);
    auto* dst = reinterpret_cast<sockaddr_in*>(&h.destination);
    src->sin_family = dst->sin_family = AF_INET;
    std::memcpy(&src->sin_addr, block, 4);
    std::memcpy(&dst->sin_addr, block + 4, 4);
    std::memcpy(&src->sin_port, block + 8, 2);  // both network order
    std::memcpy(&dst->sin_port, block + 10, 2);
  } else {
    auto* src = reinterpret_cast<sockaddr_in6*>(&h.source);
    auto* dst = reinterpret_cast<sockaddr_in6*>(&h.destination);
    src->sin6_family = dst->sin6_family = AF_INET6;
    std::memcpy(&src->sin6_addr, block, 16);
    std::memcpy(&dst->sin6_addr, block + 16, 16);
    std::memcpy(&src->sin6_port, block + 32, 2);
    std::memcpy(&dst->sin6_port, block + 34, 2);
  }
}

}  // namespace

ProxyParse parse_proxy_header(std::span<const uint8_t> bytes) {
  const size_t have = bytes.size();
  const size_t signature_seen = std::min(have, sizeof kSignature);
  if (signature_seen > 0 && std::memcmp(bytes.data(), kSignature, signature_seen) != 0)
    return error("not a PROXY protocol v2 signature (this listener expects one first, --listen-proxied)");
  if (have > sizeof kSignature) {
    const uint8_t ver_cmd = bytes[12];
    if ((ver_cmd >> 4) != 2) return error("PROXY header version " + std::to_string(ver_cmd >> 4) + ", expected 2");
    if ((ver_cmd & 0x0F) > 1) return error("PROXY header command " + hex(ver_cmd & 0x0F) + " is neither LOCAL nor PROXY");
  }
  if (have < kProxyFixedBytes) return {};
  const bool local = (bytes[12] & 0x0F) == 0;
  const uint8_t family = bytes[13] >> 4, transport = bytes[13] & 0x0F;
  // LOCAL: "discard the protocol block including the family which is ignored" (spec 2.2).
  if (!local && (family > 3 || transport > 2))
    return error("PROXY header family/transport byte " + hex(bytes[13]) + " is not one the protocol defines");
  const size_t length = be16(bytes.data() + 14);
  const size_t total = kProxyFixedBytes + length;
  if (total > kProxyMaxBytes)
    return error("PROXY header of " + std::to_string(total) + " bytes is longer than the " +
                 std::to_string(kProxyMaxBytes) + " accepted");
  const bool tcp = transport == 1 && (family == 1 || family == 2);
  const size_t address_bytes = family == 1 ? 12 : family == 2 ? 36 : family == 3 ? 216 : 0;
  if (!local && length < address_bytes)
    return error("PROXY header family/transport " + hex(bytes[13]) + " needs " + std::to_string(address_bytes) +
                 " address bytes, its length says " + std::to_string(length));
  if (have < total) {
    ProxyParse p;
    p.need = total;
    return p;
  }
  ProxyParse p;
  p.status = ProxyParse::Status::Complete;
  p.header.command = local ? ProxyHeader::Command::Local : ProxyHeader::Command::Proxy;
  p.header.size = total;
  // TLVs after the addresses are covered by the length and skipped.
  if (!local && tcp) read_addresses(family, bytes.data() + kProxyFixedBytes, p.header);
  return p;
}

}  // namespace dn::server::net
