// The chaos case: a real dnserver killed with SIGKILL
// mid-stream and started again on the same address. A plain Session gets a
// transport error that says the connection was lost; a ReconnectingSession
// reports each frame in flight as lost, reconnects, and the frames after it
// come back in order from a new session; `dnrender --server` does the same
// and finishes the run with exit code 0.
//
// Nothing here waits on time: the server is stopped (SIGSTOP) before frames
// are sent that it must never answer, then killed, so "in flight at the
// kill" does not depend on how fast anything runs.
#include <gtest/gtest.h>
#include <signal.h>

#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "dn/client/client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

using protocol::ChannelId;

constexpr uint32_t kWidth = 64, kHeight = 36;

client::SessionDesc passthrough_desc(uint32_t in_flight) {
  client::SessionDesc d;
  d.width = kWidth;
  d.height = kHeight;
  d.pipeline = "passthrough";
  d.max_in_flight = in_flight;
  d.channel(ChannelId::Radiance);
  return d;
}

// Radiance = the frame index everywhere, so a result shows which frame it is.
struct IndexedFrame {
  std::vector<float> radiance;
  client::FrameInput input;
  explicit IndexedFrame(uint64_t index) : radiance(size_t{kWidth} * kHeight * 3, static_cast<float>(index)) {
    input.frame_index = index;
    input.add(ChannelId::Radiance, std::span<const float>(radiance));
  }
};

void expect_result_of(const client::Result& r, uint64_t index) {
  EXPECT_EQ(r.frame_index, index);
  const std::vector<float> rgb = r.rgb();
  EXPECT_EQ(rgb.front(), static_cast<float>(index)) << "frame " << index << " came back with another frame's pixels";
  EXPECT_EQ(rgb.back(), static_cast<float>(index));
}

// Stops the server (it answers nothing more), then kills it: what the client
// sent in between is in flight at the kill, however fast anything runs.
struct Addresses {
  std::string tcp, unix_socket;
};
Addresses addresses(ServerProcess& s) { return {s.tcp_url(), s.unix_url()}; }

std::unique_ptr<ServerProcess> restart_on(const Addresses& a) {
  return std::make_unique<ServerProcess>(std::vector<std::string>{"--listen", a.tcp, "--listen", a.unix_socket},
                                         /*add_listeners=*/false);
}

class ServerKilled : public ::testing::TestWithParam<bool> {  // true: TCP, false: the Unix socket
 protected:
  std::string url_of(ServerProcess& s) { return GetParam() ? s.tcp_url() : s.unix_url(); }
};

TEST_P(ServerKilled, PlainSessionGetsAnErrorSayingTheConnectionWasLost) {
  auto server = std::make_unique<ServerProcess>();
  const std::string url = url_of(*server);
  auto conn = client::Connection::connect(url);
  client::Session session = conn.open_session(passthrough_desc(4));
  IndexedFrame f0(0);
  expect_result_of(session.denoise(f0.input), 0);

  ASSERT_EQ(::kill(server->pid(), SIGSTOP), 0);
  IndexedFrame f1(1);
  session.submit(f1.input);
  server->signal_and_wait(SIGKILL);
  try {
    session.wait();
    FAIL() << "expected a transport error for frame 1";
  } catch (const client::Error& e) {
    EXPECT_EQ(e.kind(), client::ErrorKind::Transport) << e.what();
    const std::string what = e.what();
    EXPECT_NE(what.find("transport error on " + url + ": connection lost: the server"), std::string::npos) << what;
  }
}

TEST_P(ServerKilled, ReconnectingSessionReportsFramesInFlightAndGoesOnInANewSession) {
  auto server = std::make_unique<ServerProcess>();
  const Addresses where = addresses(*server);
  const std::string url = url_of(*server);

  std::vector<client::Reconnected> reconnections;
  client::ReconnectOptions ro;
  ro.give_up_after = std::chrono::seconds(120);  // a restart on a loaded machine with a cold shader cache
  ro.on_reconnect = [&](const client::Reconnected& r) { reconnections.push_back(r); };
  client::ConnectOptions co;
  co.io_timeout = std::chrono::seconds(60);
  client::ReconnectingSession s(url, passthrough_desc(4), co, ro);
  ASSERT_NE(s.session(), nullptr);
  const uint64_t first_session = s.session()->id();

  // Frames 0-5 on the first server, in order.
  for (uint64_t i = 0; i < 6; ++i) {
    IndexedFrame f(i);
    EXPECT_EQ(s.submit(f.input), i);
    expect_result_of(s.wait(), i);
  }

  // Frames 6-8 go to a server that will never answer them.
  ASSERT_EQ(::kill(server->pid(), SIGSTOP), 0);
  for (uint64_t i = 6; i < 9; ++i) {
    IndexedFrame f(i);
    EXPECT_EQ(s.submit(f.input), i);
  }
  EXPECT_EQ(s.in_flight(), 3u);
  server->signal_and_wait(SIGKILL);
  server = restart_on(where);

  // Each is reported lost, by index, in order: never dropped in silence.
  for (uint64_t i = 6; i < 9; ++i) {
    try {
      s.wait();
      FAIL() << "frame " << i << " was answered by a killed server";
    } catch (const client::Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(e.kind(), client::ErrorKind::Transport) << what;
      EXPECT_NE(what.find("transport error on " + url + ": frame " + std::to_string(i) + " lost: "), std::string::npos)
          << what;
      EXPECT_NE(what.find("history reset"), std::string::npos) << what;
    }
  }
  EXPECT_EQ(s.in_flight(), 0u);
  EXPECT_EQ(s.frames_lost(), 3u);
  EXPECT_TRUE(reconnections.empty()) << "reconnects on the next submit, not before";

  // Frames 9-20: a new session on the new server, pipelined, in order.
  uint64_t expected = 9;
  for (uint64_t i = 9; i <= 20; ++i) {
    IndexedFrame f(i);
    EXPECT_EQ(s.submit(f.input), i);
    while (auto r = s.poll()) expect_result_of(*r, expected++);
  }
  while (s.in_flight() > 0) expect_result_of(s.wait(), expected++);
  EXPECT_EQ(expected, 21u);

  ASSERT_EQ(reconnections.size(), 1u);
  EXPECT_EQ(s.reconnections(), 1u);
  const client::Reconnected& r = reconnections[0];
  EXPECT_EQ(r.old_session_id, first_session);
  EXPECT_EQ(r.new_session_id, s.session()->id());
  EXPECT_NE(r.new_session_id, first_session);
  EXPECT_EQ(r.first_frame_index, 9u);
  EXPECT_EQ(r.frames_lost, 3u);
  EXPECT_EQ(r.endpoint, url);
  EXPECT_NE(r.cause.find("connection lost"), std::string::npos) << r.cause;
  s.close();
}

INSTANTIATE_TEST_SUITE_P(Transports, ServerKilled, ::testing::Values(true, false),
                         [](const ::testing::TestParamInfo<bool>& i) { return i.param ? "Tcp" : "Unix"; });

TEST(ServerKilledUnderDnrender, ItReconnectsResetsHistoryAndFinishes) {
  auto server = std::make_unique<ServerProcess>();
  const Addresses where = addresses(*server);
  constexpr int kFrames = 200;  // far more than can be answered before the server stops (window of 2)
  ChildProcess render(DN_DNRENDER_PATH, {"--scene", "1", "--width", std::to_string(kWidth), "--height",
                                         std::to_string(kHeight), "--spp", "1", "--threads", "1", "--frames",
                                         std::to_string(kFrames), "--server", where.tcp, "--pipeline", "accumulate",
                                         "--reconnect-for", "120"});
  ASSERT_TRUE(render.read_until("dnrender: denoised frame 2 ", 120)) << render.output();

  ASSERT_EQ(::kill(server->pid(), SIGSTOP), 0);
  ASSERT_TRUE(render.running()) << "dnrender finished before the server was stopped:\n" << render.output();
  server->signal_and_wait(SIGKILL);
  server = restart_on(where);

  const int status = render.wait(240);
  const std::string out = render.output();
  EXPECT_EQ(status, 0) << out;
  EXPECT_NE(out.find("dnrender: reconnected to " + where.tcp + " after losing session "), std::string::npos) << out;
  EXPECT_NE(out.find("history reset"), std::string::npos) << out;
  EXPECT_NE(out.find(" lost: "), std::string::npos) << "the frames in flight at the kill are reported\n" << out;
  EXPECT_NE(out.find("dnrender: denoised frame " + std::to_string(kFrames - 1) + " "), std::string::npos) << out;

  // The new session's id and watch command are printed again, as at the start:
  // the old ones name a session that is gone.
  std::smatch first, reconnected, hint;
  const std::string watch_line = "dnrender: session ([0-9]+) \\(watch it with: DN_WATCH_KEY=([0-9a-f]{32}) dn watch "
                                 "--server " + where.tcp + " --session ([0-9]+) --output 'watch/%04d.png'\\)";
  ASSERT_TRUE(std::regex_search(out, first, std::regex(watch_line))) << out;
  EXPECT_EQ(first[1], first[3]);
  ASSERT_TRUE(std::regex_search(out, reconnected, std::regex("after losing session ([0-9]+) .*new session ([0-9]+) from")))
      << out;
  EXPECT_EQ(reconnected[1], first[1]);
  const std::string after = reconnected.suffix();
  ASSERT_TRUE(std::regex_search(after, hint, std::regex(watch_line))) << "no watch hint after the reconnection\n" << out;
  EXPECT_EQ(hint[1], reconnected[2]);
  EXPECT_EQ(hint[3], reconnected[2]);
  EXPECT_NE(hint[1], first[1]);
  EXPECT_NE(hint[2], first[2]) << "a new session has a new watch key";
}

}  // namespace
}  // namespace dn::test
