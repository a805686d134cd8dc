// Session lifecycle against a real dnserver process: open, frames in order,
// watchers, close, memory accounting, limits and graceful shutdown.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/socket.h>

#include <cstring>
#include <map>

#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

using protocol::ErrorCode;

TEST(Session, WelcomeDescribesServer) {
  ServerProcess server;
  RawClient c(server.tcp_url());
  auto w = c.hello();
  EXPECT_FALSE(w.device_name.empty());
  EXPECT_GT(w.limits.max_message_bytes, 0u);
  EXPECT_EQ(w.limits.max_sessions, 16u);
  bool has_passthrough = false, has_accumulate = false;
  for (const auto& p : w.pipelines) {
    has_passthrough |= p.name == "passthrough";
    has_accumulate |= p.name == "accumulate";
  }
  EXPECT_TRUE(has_passthrough);
  EXPECT_TRUE(has_accumulate);
}

TEST(Session, UnixSocketServesLikeTcp) {
  ServerProcess server;
  RawClient c(server.unix_url());
  c.hello();
  auto request = passthrough_session(32, 16);
  uint64_t sid = c.open(request);
  auto f = make_frame(sid, 0, 32, 16, request.channels, 2.5f);
  c.send(f.frame, 3);
  auto r = c.receive();
  ASSERT_TRUE(r);
  auto* result = std::get_if<protocol::Result>(&r->message);
  ASSERT_NE(result, nullptr);
  EXPECT_EQ(first_output_value(*result), 2.5f);
}

TEST(Session, PipelinedFramesReturnInOrderWithTimings) {
  ServerProcess server;
  RawClient c(server.tcp_url());
  c.hello();
  auto request = passthrough_session(64, 32);
  uint64_t sid = c.open(request);
  for (uint64_t i = 0; i < 12; ++i) {
    auto f = make_frame(sid, i * 2, 64, 32, request.channels, static_cast<float>(i));
    c.send(f.frame, 100 + i);
  }
  for (uint64_t i = 0; i < 12; ++i) {
    auto r = c.receive();
    ASSERT_TRUE(r) << "result " << i << " missing";
    auto* result = std::get_if<protocol::Result>(&r->message);
    ASSERT_NE(result, nullptr);
    EXPECT_EQ(r->header.request_id, 100 + i);
    EXPECT_EQ(result->frame_index, i * 2);
    EXPECT_EQ(first_output_value(*result), static_cast<float>(i));
    bool has_upload = false, has_download = false;
    for (const auto& t : result->timings) {
      has_upload |= t.name == "upload";
      has_download |= t.name == "download";
      EXPECT_GE(t.milliseconds, 0.0);
    }
    EXPECT_TRUE(has_upload && has_download);
  }
}

TEST(Session, NoOutputFlagSkipsPlanes) {
  ServerProcess server;
  RawClient c(server.tcp_url());
  c.hello();
  auto request = passthrough_session(32, 16);
  uint64_t sid = c.open(request);
  auto f = make_frame(sid, 0, 32, 16, request.channels, 1.0f);
  c.send(f.frame, 5, protocol::kFlagNoOutput);
  auto r = c.receive();
  ASSERT_TRUE(r);
  auto* result = std::get_if<protocol::Result>(&r->message);
  ASSERT_NE(result, nullptr);
  EXPECT_TRUE(result->planes.empty());
  EXPECT_FALSE(result->timings.empty());
}

TEST(Session, Fp16InputsAndOutput) {
  ServerProcess server;
  RawClient c(server.tcp_url());
  c.hello();
  auto request = passthrough_session(32, 16);
  request.channels[0].format = protocol::Format::F16;
  request.output_format = protocol::Format::F16;
  uint64_t sid = c.open(request);
  auto f = make_frame(sid, 0, 32, 16, request.channels, 0.333f);
  c.send(f.frame, 5);
  auto r = c.receive();
  ASSERT_TRUE(r);
  auto* result = std::get_if<protocol::Result>(&r->message);
  ASSERT_NE(result, nullptr);
  ASSERT_EQ(result->planes.at(0).bytes.size(), 32u * 16 * 3 * 2);
  uint16_t h;
  std::memcpy(&h, result->planes[0].bytes.data(), 2);
  EXPECT_EQ(h, protocol::float_to_half(0.333f));
}

// The F_beta table is computed at start-up and its time reported, before any session.
TEST(Session, StatsReportTheFbLutComputeTime) {
  ServerProcess server;
  RawClient c(server.tcp_url());
  c.hello();
  const auto st = stats(c);
  ASSERT_TRUE(st.count("fb_lut_ms"));
  EXPECT_GT(st.at("fb_lut_ms"), 0.0);
  EXPECT_LT(st.at("fb_lut_ms"), 60000.0);
}

TEST(Session, CloseFreesDeviceMemoryAndWaitsForFrames) {
  ServerProcess server;
  RawClient c(server.tcp_url());
  c.hello();
  EXPECT_EQ(stats(c)["device_bytes"], 0.0);
  auto request = passthrough_session(128, 64);
  uint64_t sid = c.open(request);
  EXPECT_GT(stats(c)["device_bytes"], 0.0);
  for (uint64_t i = 0; i < 3; ++i) {
    auto f = make_frame(sid, i, 128, 64, request.channels, 1.0f);
    c.send(f.frame, 10 + i);
  }
  c.send(protocol::CloseSession{sid}, 20);
  // Every frame sent before CLOSE_SESSION is answered first, then SESSION_CLOSED.
  for (uint64_t i = 0; i < 3; ++i) {
    auto r = c.receive();
    ASSERT_TRUE(r);
    ASSERT_NE(std::get_if<protocol::Result>(&r->message), nullptr);
    EXPECT_EQ(r->header.request_id, 10 + i);
  }
  auto closed = c.receive();
  ASSERT_TRUE(closed);
  auto* sc = std::get_if<protocol::SessionClosed>(&closed->message);
  ASSERT_NE(sc, nullptr);
  EXPECT_EQ(sc->session_id, sid);
  EXPECT_EQ(sc->frames_processed, 3u);
  EXPECT_EQ(closed->header.request_id, 20u);
  EXPECT_EQ(stats(c)["device_bytes"], 0.0);
}

TEST(Session, DisconnectFreesDeviceMemory) {
  ServerProcess server;
  {
    RawClient c(server.tcp_url());
    c.hello();
    auto request = passthrough_session(128, 64);
    uint64_t sid = c.open(request);
    auto f = make_frame(sid, 0, 128, 64, request.channels, 1.0f);
    c.send(f.frame, 1);
  }
  RawClient probe(server.tcp_url());
  probe.hello();
  std::map<std::string, double> s;
  for (int i = 0; i < 100; ++i) {
    s = stats(probe);
    if (s["sessions"] == 0 && s["device_bytes"] == 0) break;
    usleep(50000);
  }
  EXPECT_EQ(s["sessions"], 0.0);
  EXPECT_EQ(s["device_bytes"], 0.0);
}

TEST(Session, WatcherSeesTheOwnersFrames) {
  ServerProcess server;
  RawClient owner(server.tcp_url());
  owner.hello();
  auto request = passthrough_session(32, 16);
  const protocol::Session opened = owner.open_session(request);
  const uint64_t sid = opened.session_id;
  RawClient watcher(server.tcp_url());
  watcher.hello();
  watcher.send(protocol::Attach{sid, opened.watch_key}, 8);
  auto ack = watcher.receive();
  ASSERT_TRUE(ack);
  auto* s = std::get_if<protocol::Session>(&ack->message);
  ASSERT_NE(s, nullptr);
  EXPECT_TRUE(s->read_only);
  EXPECT_EQ(s->width, 32u);

  auto f = make_frame(sid, 0, 32, 16, request.channels, 4.0f);
  owner.send(f.frame, 9, protocol::kFlagNoOutput);  // the owner needs no pixels; the watcher still gets them
  auto mine = owner.receive();
  ASSERT_TRUE(mine);
  EXPECT_TRUE(std::get<protocol::Result>(mine->message).planes.empty());
  auto seen = watcher.receive();
  ASSERT_TRUE(seen);
  auto* result = std::get_if<protocol::Result>(&seen->message);
  ASSERT_NE(result, nullptr);
  EXPECT_EQ(first_output_value(*result), 4.0f);

  // A watcher cannot send frames into the session.
  watcher.send(f.frame, 10);
  auto refused = watcher.receive();
  ASSERT_TRUE(refused);
  auto* e = std::get_if<protocol::Error>(&refused->message);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->code, ErrorCode::UnknownSession);

  owner.send(protocol::CloseSession{sid}, 11);
  auto bye = watcher.receive();
  ASSERT_TRUE(bye);
  EXPECT_NE(std::get_if<protocol::SessionClosed>(&bye->message), nullptr);
}

TEST(Session, SlowWatcherGetsTheLatestFrameAndNeverSlowsTheOwner) {
  ServerProcess server;
  RawClient owner(server.tcp_url());
  owner.hello();
  constexpr uint32_t w = 256, h = 144;  // 442 KB per result
  auto request = passthrough_session(w, h);
  const protocol::Session opened = owner.open_session(request);
  const uint64_t sid = opened.session_id;
  RawClient watcher(server.tcp_url());
  int small = 64 * 1024;
  ::setsockopt(watcher.fd(), SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  watcher.hello();
  watcher.send(protocol::Attach{sid, opened.watch_key}, 8);
  ASSERT_TRUE(watcher.receive());  // SESSION (read-only)

  // The watcher reads nothing while the owner streams: the owner must not be slowed.
  constexpr int kFrames = 60;  // 26 MB of results, more than the socket buffers hold
  for (int i = 0; i < kFrames; ++i) {
    auto f = make_frame(sid, static_cast<uint64_t>(i), w, h, request.channels, static_cast<float>(i));
    owner.send(f.frame, static_cast<uint64_t>(i));
    auto r = owner.receive(20.0);
    ASSERT_TRUE(r) << "owner stalled at frame " << i;
    ASSERT_NE(std::get_if<protocol::Result>(&r->message), nullptr);
  }
  // Now the watcher reads what it was kept: fewer than all frames, ending with the latest.
  int received = 0;
  float last = -1.0f;
  while (auto r = watcher.receive(2.0)) {
    auto* result = std::get_if<protocol::Result>(&r->message);
    ASSERT_NE(result, nullptr);
    std::memcpy(&last, result->planes.at(0).bytes.data(), 4);
    ++received;
  }
  EXPECT_LT(received, kFrames) << "a slow watcher was sent every frame";
  EXPECT_GT(received, 0);
  EXPECT_EQ(last, static_cast<float>(kFrames - 1)) << "the watcher's last frame is not the latest";
}

TEST(Session, SessionLimitGivesClearError) {
  ServerProcess server({"--max-sessions", "2"});
  RawClient c(server.tcp_url());
  c.hello();
  auto request = passthrough_session(16, 16);
  c.open(request, 1);
  c.open(request, 2);
  c.send(request, 3);
  auto r = c.receive();
  ASSERT_TRUE(r);
  auto* e = std::get_if<protocol::Error>(&r->message);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->code, ErrorCode::LimitExceeded);
  EXPECT_NE(e->message.find("max-sessions"), std::string::npos) << e->message;
}

TEST(Session, SessionMemoryLimitGivesClearError) {
  ServerProcess server({"--max-session-memory", "64K"});
  RawClient c(server.tcp_url());
  c.hello();
  c.send(passthrough_session(256, 144), 3);
  auto r = c.receive();
  ASSERT_TRUE(r);
  auto* e = std::get_if<protocol::Error>(&r->message);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->code, ErrorCode::LimitExceeded);
  EXPECT_NE(e->message.find("device memory"), std::string::npos) << e->message;
}

TEST(Session, ResolutionLimit) {
  ServerProcess server({"--max-resolution", "100x100"});
  RawClient c(server.tcp_url());
  c.hello();
  c.send(passthrough_session(101, 10), 3);
  auto r = c.receive();
  ASSERT_TRUE(r);
  auto* e = std::get_if<protocol::Error>(&r->message);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->code, ErrorCode::LimitExceeded);
  EXPECT_EQ(e->field, "OPEN_SESSION.width");
}

TEST(Session, HandshakeDeadline) {
  ServerProcess server({"--handshake-timeout", "0.5"});
  RawClient c(server.tcp_url());
  auto r = c.receive(10.0);
  ASSERT_TRUE(r);
  auto* e = std::get_if<protocol::Error>(&r->message);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->code, ErrorCode::Timeout);
  EXPECT_TRUE(c.closed_by_server());
}

TEST(Session, HeartbeatThenIdleTimeout) {
  ServerProcess server({"--heartbeat", "0.3", "--idle-timeout", "1.5"});
  RawClient c(server.tcp_url());
  c.hello();
  auto ping = c.receive(5.0);
  ASSERT_TRUE(ping);
  ASSERT_NE(std::get_if<protocol::Ping>(&ping->message), nullptr) << "no heartbeat PING";
  // Answering keeps the connection alive past the idle timeout...
  for (int i = 0; i < 4; ++i) {
    c.send(protocol::Pong{std::get<protocol::Ping>(ping->message).payload}, 0);
    usleep(500000);
  }
  c.send(protocol::Ping{3}, 8);
  bool alive = false;
  for (int i = 0; i < 10 && !alive; ++i) {
    auto r = c.receive(2.0);
    ASSERT_TRUE(r) << "closed although it answered every heartbeat";
    alive = std::get_if<protocol::Pong>(&r->message) != nullptr;
  }
  EXPECT_TRUE(alive);
  // ...silence does not.
  std::optional<protocol::Error> timeout;
  for (int i = 0; i < 20 && !timeout; ++i) {
    auto r = c.receive(5.0);
    if (!r) break;
    if (auto* e = std::get_if<protocol::Error>(&r->message)) timeout = *e;
  }
  ASSERT_TRUE(timeout);
  EXPECT_EQ(timeout->code, ErrorCode::Timeout);
  EXPECT_TRUE(c.closed_by_server());
}

TEST(Session, SigtermFinishesFramesInFlight) {
  ServerProcess server;
  RawClient c(server.tcp_url());
  c.hello();
  auto request = passthrough_session(256, 144);
  uint64_t sid = c.open(request);
  for (uint64_t i = 0; i < 4; ++i) {
    auto f = make_frame(sid, i, 256, 144, request.channels, static_cast<float>(i));
    c.send(f.frame, 70 + i);
  }
  // Make sure the server has read all four before the signal.
  c.send(protocol::Ping{1}, 99);
  std::vector<uint64_t> got;
  bool ponged = false;
  while (!ponged) {
    auto r = c.receive();
    ASSERT_TRUE(r);
    if (std::get_if<protocol::Pong>(&r->message)) ponged = true;
    if (std::get_if<protocol::Result>(&r->message)) got.push_back(r->header.request_id);
  }
  ::kill(server.pid(), SIGTERM);
  while (got.size() < 4) {
    auto r = c.receive();
    ASSERT_TRUE(r) << "frame lost at shutdown after " << got.size() << "\n" << server.log();
    ASSERT_NE(std::get_if<protocol::Result>(&r->message), nullptr);
    got.push_back(r->header.request_id);
  }
  EXPECT_EQ(got, (std::vector<uint64_t>{70, 71, 72, 73}));
  EXPECT_EQ(server.signal_and_wait(0, 30.0), 0) << server.log();
  EXPECT_NE(server.log().find("event=stopped"), std::string::npos);
}

}  // namespace
}  // namespace dn::test
