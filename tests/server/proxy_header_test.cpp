// parse_proxy_header against headers written byte by byte from haproxy's
// doc/proxy-protocol.txt, section 2.2 (proxy_v2_bytes.hpp, not the parser's code).
#include "server/net/proxy_header.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>

#include <cstring>
#include <string>
#include <vector>

#include "proxy_v2_bytes.hpp"

namespace dn::server::net {
namespace {

using Status = ProxyParse::Status;
using Bytes = std::vector<uint8_t>;

using test::proxy_v2;
const Bytes& kSignature = test::kProxyV2Signature;
// 203.0.113.7:4242 -> 192.0.2.1:7001, as HAProxy's send-proxy-v2 writes it.
const Bytes kIpv4Block = {203, 0, 113, 7, 192, 0, 2, 1, 0x10, 0x92, 0x1B, 0x59};

std::string address_of(const sockaddr_storage& a) {
  char text[INET6_ADDRSTRLEN] = "";
  if (a.ss_family == AF_INET) inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(&a)->sin_addr, text, sizeof text);
  if (a.ss_family == AF_INET6) inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(&a)->sin6_addr, text, sizeof text);
  return text;
}
uint16_t port_of(const sockaddr_storage& a) {
  if (a.ss_family == AF_INET) return ntohs(reinterpret_cast<const sockaddr_in*>(&a)->sin_port);
  return ntohs(reinterpret_cast<const sockaddr_in6*>(&a)->sin6_port);
}

TEST(ProxyHeader, ProxyOverIpv4GivesTheClientsAddressAndPort) {
  const Bytes h = proxy_v2(0x21, 0x11, kIpv4Block);
  ProxyParse p = parse_proxy_header(h);
  ASSERT_EQ(p.status, Status::Complete) << p.error;
  EXPECT_EQ(p.header.command, ProxyHeader::Command::Proxy);
  EXPECT_EQ(p.header.size, 28u);
  EXPECT_EQ(address_of(p.header.source), "203.0.113.7");
  EXPECT_EQ(port_of(p.header.source), 4242);
  EXPECT_EQ(address_of(p.header.destination), "192.0.2.1");
  EXPECT_EQ(port_of(p.header.destination), 7001);
}

TEST(ProxyHeader, ProxyOverIpv6GivesTheClientsAddressAndPort) {
  Bytes block = {0x20, 0x01, 0x0d, 0xb8, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x07,   // 2001:db8::7
                 0x20, 0x01, 0x0d, 0xb8, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x01,   // 2001:db8::1
                 0xC3, 0x50, 0x1B, 0x59};                                          // 50000 -> 7001
  ProxyParse p = parse_proxy_header(proxy_v2(0x21, 0x21, block));
  ASSERT_EQ(p.status, Status::Complete) << p.error;
  EXPECT_EQ(p.header.size, 16u + 36u);
  EXPECT_EQ(address_of(p.header.source), "2001:db8::7");
  EXPECT_EQ(port_of(p.header.source), 50000);
  EXPECT_EQ(address_of(p.header.destination), "2001:db8::1");
}

TEST(ProxyHeader, LocalKeepsTheSocketsPeerWhateverItsAddressBlock) {
  // HAProxy's check-send-proxy: LOCAL, usually UNSPEC with no addresses...
  ProxyParse bare = parse_proxy_header(proxy_v2(0x20, 0x00, {}));
  ASSERT_EQ(bare.status, Status::Complete) << bare.error;
  EXPECT_EQ(bare.header.command, ProxyHeader::Command::Local);
  EXPECT_EQ(bare.header.size, 16u);
  EXPECT_EQ(bare.header.source.ss_family, AF_UNSPEC);
  // ...but the length must be honoured and the family ignored (spec 2.2).
  ProxyParse with_block = parse_proxy_header(proxy_v2(0x20, 0x11, kIpv4Block));
  ASSERT_EQ(with_block.status, Status::Complete) << with_block.error;
  EXPECT_EQ(with_block.header.size, 28u);
  EXPECT_EQ(with_block.header.source.ss_family, AF_UNSPEC);
  EXPECT_EQ(parse_proxy_header(proxy_v2(0x20, 0xFF, {1, 2, 3})).status, Status::Complete);
}

TEST(ProxyHeader, UnspecUnixAndUdpFallBackToTheSocketsPeer) {
  ProxyParse unspec = parse_proxy_header(proxy_v2(0x21, 0x00, {9, 9, 9, 9}));
  ASSERT_EQ(unspec.status, Status::Complete) << unspec.error;
  EXPECT_EQ(unspec.header.command, ProxyHeader::Command::Proxy);
  EXPECT_EQ(unspec.header.size, 20u);
  EXPECT_EQ(unspec.header.source.ss_family, AF_UNSPEC);
  ProxyParse unix_stream = parse_proxy_header(proxy_v2(0x21, 0x31, Bytes(216, 'a')));
  ASSERT_EQ(unix_stream.status, Status::Complete) << unix_stream.error;
  EXPECT_EQ(unix_stream.header.size, 16u + 216u);
  EXPECT_EQ(unix_stream.header.source.ss_family, AF_UNSPEC);
  ProxyParse udp = parse_proxy_header(proxy_v2(0x21, 0x12, kIpv4Block));
  ASSERT_EQ(udp.status, Status::Complete) << udp.error;
  EXPECT_EQ(udp.header.source.ss_family, AF_UNSPEC);
}

TEST(ProxyHeader, TlvsAreSkippedAndNotOneByteMoreIsTaken) {
  Bytes rest = kIpv4Block;
  // PP2_TYPE_ALPN "dn", PP2_TYPE_NOOP of 3 bytes.
  rest.insert(rest.end(), {0x01, 0x00, 0x02, 'd', 'n', 0x04, 0x00, 0x03, 0, 0, 0});
  Bytes h = proxy_v2(0x21, 0x11, rest);
  const size_t header_size = h.size();
  h.insert(h.end(), {'D', 'N', 'P', '1'});  // the protocol's first bytes follow
  ProxyParse p = parse_proxy_header(h);
  ASSERT_EQ(p.status, Status::Complete) << p.error;
  EXPECT_EQ(p.header.size, header_size);
  EXPECT_EQ(header_size, 16u + 12u + 11u);
  EXPECT_EQ(address_of(p.header.source), "203.0.113.7");
}

TEST(ProxyHeader, SplitAcrossReadsAsksForExactlyTheHeader) {
  Bytes rest = kIpv4Block;
  rest.insert(rest.end(), {0x04, 0x00, 0x02, 0, 0});
  const Bytes h = proxy_v2(0x21, 0x11, rest);
  // Every prefix: NeedMore, asking for the fixed part and then for the whole header.
  for (size_t n = 0; n < h.size(); ++n) {
    ProxyParse p = parse_proxy_header(std::span(h.data(), n));
    ASSERT_EQ(p.status, Status::NeedMore) << "after " << n << " bytes: " << p.error;
    EXPECT_EQ(p.need, n < 16 ? 16u : h.size()) << "after " << n << " bytes";
  }
  ProxyParse p = parse_proxy_header(h);
  ASSERT_EQ(p.status, Status::Complete);
  EXPECT_EQ(address_of(p.header.source), "203.0.113.7");
}

void expect_error(const Bytes& bytes, const std::string& words) {
  ProxyParse p = parse_proxy_header(bytes);
  ASSERT_EQ(p.status, Status::Error) << "accepted a bad header, expected an error naming '" << words << "'";
  EXPECT_NE(p.error.find(words), std::string::npos) << p.error;
}

TEST(ProxyHeader, AWrongSignatureIsRefusedAtItsFirstWrongByte) {
  expect_error({0x0D, 0x0A, 0x0D, 0x0B}, "signature");
  // The protocol's own header (magic "DN"…) on a proxied listener.
  expect_error({'D', 'N'}, "signature");
  // PROXY v1 text is not accepted.
  const std::string v1 = "PROXY TCP4 203.0.113.7 192.0.2.1 4242 7001\r\n";
  expect_error(Bytes(v1.begin(), v1.end()), "signature");
  Bytes last_wrong = proxy_v2(0x21, 0x11, kIpv4Block);
  last_wrong[11] = 0x0B;
  expect_error(last_wrong, "signature");
}

TEST(ProxyHeader, VersionOtherThanTwoIsRefused) {
  expect_error(proxy_v2(0x11, 0x11, kIpv4Block), "version 1");
  Bytes just_version = kSignature;
  just_version.push_back(0x31);
  expect_error(just_version, "version 3");
}

TEST(ProxyHeader, UnknownCommandIsRefused) { expect_error(proxy_v2(0x22, 0x11, kIpv4Block), "command 0x02"); }

TEST(ProxyHeader, UnknownFamilyOrTransportIsRefused) {
  expect_error(proxy_v2(0x21, 0x41, kIpv4Block), "0x41");
  expect_error(proxy_v2(0x21, 0x13, kIpv4Block), "0x13");
}

TEST(ProxyHeader, ALengthTooShortForTheFamilyIsRefused) {
  expect_error(proxy_v2(0x21, 0x11, {203, 0, 113, 7}), "needs 12");
  expect_error(proxy_v2(0x21, 0x21, kIpv4Block), "needs 36");
  expect_error(proxy_v2(0x21, 0x31, Bytes(100, 0)), "needs 216");
}

TEST(ProxyHeader, AHeaderLongerThanTheLimitIsRefusedFromItsLengthAlone) {
  // Only the fixed 16 bytes: the declared length already says too long.
  expect_error(proxy_v2(0x21, 0x11, {}, static_cast<int>(kProxyMaxBytes - 16 + 1)), "longer than the 536");
  expect_error(proxy_v2(0x21, 0x11, {}, 0xFFFF), "65551 bytes");
  // Exactly the limit is accepted.
  Bytes rest = kIpv4Block;
  rest.resize(kProxyMaxBytes - 16, 0);
  EXPECT_EQ(parse_proxy_header(proxy_v2(0x21, 0x11, rest)).status, Status::Complete);
}

}  // namespace
}  // namespace dn::server::net
