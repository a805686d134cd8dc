// dnserver behind a balancer: a real server with a --listen-proxied listener,
// clients that send what HAProxy's send-proxy-v2 / check-send-proxy send
// (proxy_v2_bytes.hpp), and the plain listener beside it.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <chrono>
#include <sstream>
#include <string>
#include <thread>

#include "proxy_v2_bytes.hpp"
#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

using protocol::ErrorCode;

constexpr const char* kToken = "balancer-shared-token";

// The log lines holding every one of `words`.
std::vector<std::string> lines_with(const std::string& log, std::initializer_list<std::string> words) {
  std::vector<std::string> found;
  std::istringstream in(log);
  for (std::string line; std::getline(in, line);) {
    bool all = true;
    for (const std::string& w : words) all = all && line.find(w) != std::string::npos;
    if (all) found.push_back(line);
  }
  return found;
}

// A server with its plain loopback TCP and Unix listeners plus one proxied
// listener; a proxied listener needs a token (given through DN_TOKEN).
class ProxyProtocol : public ::testing::Test {
 protected:
  void SetUp() override { ::setenv("DN_TOKEN", kToken, 1); }
  void TearDown() override { ::unsetenv("DN_TOKEN"); }

  void start(std::vector<std::string> args = {}) {
    args.insert(args.end(), {"--listen-proxied", "tcp://127.0.0.1:0"});
    server_ = std::make_unique<ServerProcess>(args);
    auto listen = lines_with(server_->log(), {"event=listen", "proxy_protocol=v2"});
    ASSERT_EQ(listen.size(), 1u) << server_->log();
    const size_t at = listen[0].find("url=") + 4;
    proxied_url_ = listen[0].substr(at, listen[0].find(' ', at) - at);
  }

  // A connection to the proxied listener that sent `header` first.
  RawClient connect_with(const std::vector<uint8_t>& header) {
    RawClient c(proxied_url_);
    c.send_bytes(header);
    return c;
  }

  std::unique_ptr<ServerProcess> server_;
  std::string proxied_url_;
};

// The first `n` bytes of `bytes`. A refused connection is sent only what the
// server reads before it refuses: bytes left unread when it closes make the
// kernel answer with a reset, which may discard the ERROR still on its way.
std::vector<uint8_t> first(const std::vector<uint8_t>& bytes, size_t n) { return {bytes.begin(), bytes.begin() + n}; }

// The ERROR received, or nullopt for anything else (a copy: the message goes with `r`).
std::optional<protocol::Error> error_of(const std::optional<Received>& r) {
  if (auto* e = r ? std::get_if<protocol::Error>(&r->message) : nullptr) return *e;
  return std::nullopt;
}

TEST(ProxyProtocolStart, AProxiedListenerWithoutATokenRefusesToStartEvenOnLoopback) {
  std::string out;
  EXPECT_NE(run_dnserver({"--listen-proxied", "tcp://127.0.0.1:0"}, out), 0);
  EXPECT_NE(out.find("--listen-proxied tcp://127.0.0.1:0 is reached through a balancer"), std::string::npos) << out;
  EXPECT_NE(out.find("token"), std::string::npos) << out;
}

TEST_F(ProxyProtocol, TheForwardedSourceIsThePeerInTheLog) {
  start();
  RawClient c = connect_with(proxy_v2_ipv4({203, 0, 113, 7}, 4242));
  EXPECT_NO_THROW(c.hello(kToken));
  const std::string log = server_->log();
  // The socket's peer is this process on 127.0.0.1; the log names the client the balancer forwarded.
  EXPECT_EQ(lines_with(log, {"event=connection.hello", "peer=203.0.113.7:4242"}).size(), 1u) << log;
  auto proxied = lines_with(log, {"event=connection.proxied", "peer=203.0.113.7:4242", "command=PROXY",
                                  "identity=ip:203.0.113.7", "via=127.0.0.1:"});
  EXPECT_EQ(proxied.size(), 1u) << log;
}

TEST_F(ProxyProtocol, AHeaderSplitAcrossWritesIsReassembled) {
  start();
  const std::vector<uint8_t> header = proxy_v2_ipv4({203, 0, 113, 8}, 5151);
  RawClient c(proxied_url_);
  c.send_bytes({header.begin(), header.begin() + 5});
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the server reads the first part alone
  c.send_bytes({header.begin() + 5, header.begin() + 17});
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  c.send_bytes({header.begin() + 17, header.end()});
  EXPECT_NO_THROW(c.hello(kToken));
  EXPECT_EQ(lines_with(server_->log(), {"event=connection.hello", "peer=203.0.113.8:5151"}).size(), 1u)
      << server_->log();
}

TEST_F(ProxyProtocol, ThePerPeerLimitCountsTheForwardedAddressNotTheBalancer) {
  // All four connections come from this process (one uid on loopback): as
  // plain connections the fourth would be over a limit of 2.
  start({"--max-connections-per-peer", "2"});
  RawClient a1 = connect_with(proxy_v2_ipv4({203, 0, 113, 7}, 1001));
  RawClient a2 = connect_with(proxy_v2_ipv4({203, 0, 113, 7}, 1002));
  ASSERT_NO_THROW(a1.hello(kToken));
  ASSERT_NO_THROW(a2.hello(kToken));
  RawClient a3 = connect_with(proxy_v2_ipv4({203, 0, 113, 7}, 1003));
  auto refused = a3.receive();
  std::optional<protocol::Error> e = error_of(refused);
  ASSERT_TRUE(e) << "a third connection from 203.0.113.7 was not refused";
  EXPECT_EQ(e->code, ErrorCode::LimitExceeded);
  EXPECT_NE(e->message.find("peer ip:203.0.113.7 already has 2 connections"), std::string::npos) << e->message;
  EXPECT_TRUE(a3.closed_by_server());
  // Another forwarded client is another peer.
  RawClient b1 = connect_with(proxy_v2_ipv4({198, 51, 100, 9}, 2001));
  EXPECT_NO_THROW(b1.hello(kToken));
  // A plain connection from this process is a third peer again (uid on loopback).
  RawClient plain(server_->tcp_url());
  EXPECT_NO_THROW(plain.hello(kToken));
}

TEST_F(ProxyProtocol, ALocalHeaderIsAHealthCheckOnTheSocketsOwnPeer) {
  start();
  RawClient check = connect_with(proxy_v2_local());
  EXPECT_NO_THROW(check.hello(kToken));
  const std::string log = server_->log();
  EXPECT_EQ(lines_with(log, {"event=connection.hello", "peer=127.0.0.1:"}).size(), 1u) << log;
  EXPECT_TRUE(lines_with(log, {"event=proxy.refused"}).empty()) << log;
}

TEST_F(ProxyProtocol, GarbageInsteadOfTheHeaderIsClosedAndLoggedAndOthersGoOn) {
  start();
  RawClient good = connect_with(proxy_v2_ipv4({203, 0, 113, 7}, 4242));
  ASSERT_NO_THROW(good.hello(kToken));

  const std::string http = "GET / HTTP/1.0\r\n";  // 16 bytes: the fixed part the server reads first
  RawClient garbage = connect_with({http.begin(), http.end()});
  std::optional<protocol::Error> e = error_of(garbage.receive());
  ASSERT_TRUE(e);
  EXPECT_EQ(e->field, "proxy_header");
  EXPECT_TRUE(garbage.closed_by_server());

  // A renderer pointed at the proxied port directly: told why, not left hanging.
  std::vector<uint8_t> hello;
  protocol::encode(protocol::Hello{0, "direct", kToken}, 1, 0, hello);
  RawClient direct = connect_with(first(hello, 16));
  e = error_of(direct.receive());
  ASSERT_TRUE(e);
  EXPECT_NE(e->message.find("PROXY protocol v2"), std::string::npos) << e->message;
  EXPECT_TRUE(direct.closed_by_server());

  // Wrong version, and a header longer than the limit (its length alone says so).
  RawClient v1 = connect_with(first(proxy_v2(0x11, 0x11, ipv4_block({203, 0, 113, 7}, 1, {192, 0, 2, 1}, 2)), 16));
  EXPECT_TRUE(v1.closed_by_server());
  RawClient huge = connect_with(proxy_v2(0x21, 0x11, {}, 4000));
  EXPECT_TRUE(huge.closed_by_server());

  const std::string log = server_->log();
  EXPECT_EQ(lines_with(log, {"level=warn", "event=proxy.refused", "signature"}).size(), 2u) << log;
  EXPECT_EQ(lines_with(log, {"event=proxy.refused", "version 1, expected 2"}).size(), 1u) << log;
  EXPECT_EQ(lines_with(log, {"event=proxy.refused", "4016 bytes is longer than the 536"}).size(), 1u) << log;
  // The connection that came before is untouched.
  good.send(protocol::Ping{42}, 7);
  auto pong = good.receive();
  ASSERT_TRUE(pong);
  EXPECT_NE(std::get_if<protocol::Pong>(&pong->message), nullptr);
}

TEST_F(ProxyProtocol, AHeaderNotCompleteWithinTheHandshakeTimeoutIsClosed) {
  start({"--handshake-timeout", "1"});
  const std::vector<uint8_t> header = proxy_v2_ipv4({203, 0, 113, 7}, 4242);
  RawClient slow = connect_with({header.begin(), header.begin() + 10});
  EXPECT_TRUE(slow.closed_by_server(30.0));
  const std::string log = server_->log();
  EXPECT_EQ(lines_with(log, {"event=proxy.refused", "no complete PROXY header within"}).size(), 1u) << log;
}

TEST_F(ProxyProtocol, APlainListenerTreatsAProxyHeaderAsBadBytes) {
  start();
  RawClient c(server_->tcp_url());
  // What a balancer sends first, up to the 24 bytes of a protocol header.
  c.send_bytes(first(proxy_v2_ipv4({203, 0, 113, 7}, 4242), 24));
  std::optional<protocol::Error> e = error_of(c.receive());
  ASSERT_TRUE(e);
  EXPECT_EQ(e->code, ErrorCode::BadMagic);
  EXPECT_TRUE(c.closed_by_server());
  const std::string log = server_->log();
  EXPECT_TRUE(lines_with(log, {"203.0.113.7"}).empty()) << log;
  EXPECT_EQ(lines_with(log, {"event=protocol.framing_error"}).size(), 1u) << log;
}

}  // namespace
}  // namespace dn::test
