// Flow control against a real dnserver process: a renderer that stops
// reading is slowed, never dropped, and never slows anyone else; many
// connections at once are all served.
#include <gtest/gtest.h>
#include <sys/socket.h>

#include <cstring>
#include <thread>

#include "raw_client.hpp"
#include "server_process.hpp"
#include "well_behaved.hpp"

namespace dn::test {
namespace {

TEST(Backpressure, ClientThatStopsReadingIsSlowedNotDroppedAndDisturbsNoOne) {
  ServerProcess server({"--max-output-buffer", "1M", "--max-in-flight", "2"});
  RawClient stalled(server.tcp_url());
  int small = 64 * 1024;
  ::setsockopt(stalled.fd(), SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  stalled.hello();
  constexpr uint32_t w = 256, h = 144;  // 442 KB results: a few fill the buffers
  auto request = passthrough_session(w, h);
  uint64_t sid = stalled.open(request);

  // Send frames from a thread without reading anything back: the server must
  // stop reading from us once its window and output buffer are full.
  constexpr int kFrames = 120;
  std::atomic<int> sent{0};
  std::thread sender([&] {
    for (int i = 0; i < kFrames; ++i) {
      auto f = make_frame(sid, static_cast<uint64_t>(i), w, h, request.channels, static_cast<float>(i));
      stalled.send(f.frame, static_cast<uint64_t>(i));
      ++sent;
    }
  });
  std::this_thread::sleep_for(std::chrono::seconds(2));
  EXPECT_LT(sent.load(), kFrames) << "the server kept reading from a client that reads nothing";

  // Meanwhile another renderer is served normally.
  WellBehavedClient good(server.tcp_url(), 30);
  EXPECT_EQ(good.join(), "");

  // Now the stalled client reads: every frame comes back, in order.
  for (int i = 0; i < kFrames; ++i) {
    auto r = stalled.receive(30.0);
    ASSERT_TRUE(r) << "frame " << i << " lost";
    auto* result = std::get_if<protocol::Result>(&r->message);
    ASSERT_NE(result, nullptr);
    ASSERT_EQ(result->frame_index, static_cast<uint64_t>(i));
    float v;
    std::memcpy(&v, result->planes.at(0).bytes.data(), 4);
    EXPECT_EQ(v, static_cast<float>(i));
  }
  sender.join();
}

TEST(Backpressure, ManyConnectionsAtOnce) {
  ServerProcess server;
  WellBehavedClient good(server.tcp_url(), 30);
  std::vector<RawClient> clients;
  for (int i = 0; i < 120; ++i) clients.emplace_back(i % 2 ? server.tcp_url() : server.unix_url());
  for (auto& c : clients) c.send(protocol::Hello{0, "many", ""}, 1);
  int welcomed = 0;
  for (auto& c : clients) {
    auto r = c.receive();
    if (r && std::get_if<protocol::Welcome>(&r->message)) ++welcomed;
  }
  EXPECT_EQ(welcomed, 120);
  for (size_t i = 0; i < clients.size(); i += 3) clients[i].close();  // abrupt goodbyes
  EXPECT_EQ(good.join(), "");
}

TEST(Backpressure, ConnectionLimitGivesClearError) {
  // One peer (this process) may hold them all here: the global limit is what is tested.
  ServerProcess server({"--max-connections", "3", "--max-connections-per-peer", "3"});
  std::vector<RawClient> clients;
  for (int i = 0; i < 3; ++i) {
    clients.emplace_back(server.tcp_url());
    clients.back().hello();
  }
  RawClient extra(server.tcp_url());
  auto r = extra.receive();
  ASSERT_TRUE(r);
  auto* e = std::get_if<protocol::Error>(&r->message);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->code, protocol::ErrorCode::LimitExceeded);
  EXPECT_TRUE(extra.closed_by_server());
}

}  // namespace
}  // namespace dn::test
