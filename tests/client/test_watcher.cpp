// Watcher::next_for returns a RESULT that is already in the socket buffer at
// once, rather than reading it and then sleeping out the timeout.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "dn/client/client.hpp"
#include "fake_server.hpp"

namespace {

using namespace dn;
using namespace dn::protocol;
using dn::test::FakeServer;
using dn::test::Peer;

constexpr uint32_t W = 4, H = 2;
constexpr const char* kKey = "00112233445566778899aabbccddeeff";

TEST(Watcher, AResultAlreadyInTheSocketIsReturnedWithoutWaitingOutTheTimeout) {
  FakeServer server([&](Peer& peer) {
    peer.handshake_with(dn::test::test_welcome_with_parameters());
    auto m = peer.recv();
    ASSERT_TRUE(m);
    peer.send(dn::test::attach_reply(42, W, H), m->header.request_id);
    // After the SESSION has been read by attach(): the RESULT waits, unread, in the client's socket.
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    std::vector<uint8_t> bytes(W * H * 3 * 4, 0);
    Result r;
    r.session_id = 42;
    r.frame_index = 7;
    r.planes.push_back({ChannelId::Output, Format::F32, bytes});
    peer.send(r, m->header.request_id);
    peer.recv(30000);  // until the client goes
  });
  {
    client::Connection conn = client::Connection::connect(server.url(), {});
    client::Watcher w = conn.attach(42, kKey);
    std::this_thread::sleep_for(std::chrono::milliseconds(1000));
    const auto start = std::chrono::steady_clock::now();
    const auto r = w.next_for(std::chrono::seconds(20));
    const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_TRUE(r);
    EXPECT_EQ(r->frame_index, 7u);
    // The frame was there before the call: any wait near the 20 s timeout is the bug (generous bound).
    EXPECT_LT(waited_s, 10.0);
  }
  server.join();
}

}  // namespace
