// The connection layer alone (server/net/connection_layer.hpp), with a
// stand-in for the session service above it: HELLO, PING and framing are
// its own; every other request of an authenticated connection, and the
// connection's end, go to the RequestHandler. No device, no sessions.
#include <gtest/gtest.h>

#include <sys/socket.h>
#include <unistd.h>

#include <deque>
#include <vector>

#include "dn/protocol/codec.hpp"
#include "server/net/connection_layer.hpp"

namespace dn::server {
namespace {

using protocol::MessageType;

// Records what reaches the layer above.
class RecordingHandler final : public RequestHandler {
 public:
  void on_request(net::Connection& c, const protocol::Header& h, protocol::Message&&, std::vector<uint8_t>&&) override {
    requests.push_back(h.type);
    last_connection = c.id();
  }
  bool has_work(const net::Connection&) const override { return false; }
  bool window_full(const net::Connection&) const override { return false; }
  void on_closed(net::Connection& c) override { closed.push_back(c.id()); }

  std::vector<MessageType> requests;
  std::vector<uint64_t> closed;
  uint64_t last_connection = 0;
};

// A client on one end of a socketpair whose other end the layer adopted.
struct Peer {
  int fd = -1;
  protocol::MessageReader reader{uint64_t{1} << 24};
  std::vector<protocol::Header> received;

  void send(const protocol::Message& m, uint64_t request_id) {
    const std::vector<uint8_t> bytes = protocol::encode(m, request_id);
    ASSERT_EQ(::write(fd, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  }
  // Whatever the layer wrote so far.
  void drain() {
    for (;;) {
      std::span<uint8_t> w = reader.writable();
      const ssize_t n = ::recv(fd, w.data(), w.size(), MSG_DONTWAIT);
      if (n <= 0) return;
      auto status = reader.commit(static_cast<size_t>(n));
      while (status == protocol::MessageReader::Status::Ready) {
        received.push_back(reader.header());
        reader.take_payload();
        status = reader.commit(0);
      }
    }
  }
};

class ConnectionLayerTest : public ::testing::Test {
 protected:
  ConnectionLayerTest() : layer(options, loop, counters, "test device") { layer.set_handler(&handler); }
  ~ConnectionLayerTest() override {
    for (const Peer& p : peers)
      if (p.fd >= 0) ::close(p.fd);
  }

  Peer& connect() {
    int fds[2];
    EXPECT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds), 0);
    layer.adopt(fds[0]);
    peers.push_back(Peer{fds[1]});
    return peers.back();
  }
  void turns(int n = 5) {
    for (int i = 0; i < n; ++i) loop.run_once(10);
    for (Peer& p : peers) p.drain();
  }

  ServerOptions options;  // no listeners: peers are adopted
  net::EventLoop loop;
  ServerCounters counters;
  ConnectionLayer layer;
  RecordingHandler handler;
  std::deque<Peer> peers;  // connect() hands out references: push_back keeps them
};

TEST_F(ConnectionLayerTest, HelloAndPingAreItsOwnEveryOtherRequestGoesAbove) {
  Peer& p = connect();
  p.send(protocol::Hello{0, "test", ""}, 1);
  turns();
  ASSERT_EQ(p.received.size(), 1u);
  EXPECT_EQ(p.received[0].type, MessageType::Welcome);
  EXPECT_EQ(p.received[0].request_id, 1u);

  p.send(protocol::Ping{42}, 2);
  p.send(protocol::StatsRequest{}, 3);
  p.send(protocol::CloseSession{7}, 4);
  turns();
  ASSERT_EQ(p.received.size(), 2u);
  EXPECT_EQ(p.received[1].type, MessageType::Pong);
  EXPECT_EQ(p.received[1].request_id, 2u);
  EXPECT_EQ(handler.requests, (std::vector<MessageType>{MessageType::StatsRequest, MessageType::CloseSession}));
  EXPECT_TRUE(handler.closed.empty());

  ::close(p.fd);
  p.fd = -1;
  turns();
  EXPECT_EQ(handler.closed, std::vector<uint64_t>{handler.last_connection});
  EXPECT_EQ(layer.size(), 0u);
}

// Before HELLO nothing reaches the layer above: the request gets a fatal ERROR.
TEST_F(ConnectionLayerTest, ARequestBeforeHelloNeverReachesTheHandler) {
  Peer& p = connect();
  p.send(protocol::StatsRequest{}, 9);
  turns();
  ASSERT_EQ(p.received.size(), 1u);
  EXPECT_EQ(p.received[0].type, MessageType::Error);
  EXPECT_EQ(p.received[0].request_id, 9u);
  EXPECT_TRUE(handler.requests.empty());
}

}  // namespace
}  // namespace dn::server
