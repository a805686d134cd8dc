// dn watch against the fake server: a session that ends (SESSION_CLOSED) is a
// normal end, an ERROR on the stream or a lost connection is not.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>

#include "commands.hpp"
#include "dn/client/error.hpp"
#include "fake_server.hpp"

namespace {

using namespace dn;
using namespace dn::protocol;
using dn::test::FakeServer;
using dn::test::Peer;
namespace fs = std::filesystem;

constexpr uint32_t W = 8, H = 4;
constexpr const char* kKey = "00112233445566778899aabbccddeeff";

enum class StreamEnd { Closed, Error, Hangup };

// Answers ATTACH, streams frames 1 and 2 (frame 2, the newest, is always
// written), then ends the stream as `end` says.
void stream_then_end(Peer& peer, StreamEnd end) {
  peer.handshake_with(dn::test::test_welcome_with_parameters());
  auto m = peer.recv();
  ASSERT_TRUE(m);
  auto* a = std::get_if<Attach>(&m->message);
  ASSERT_NE(a, nullptr);
  peer.send(dn::test::attach_reply(a->session_id, W, H), m->header.request_id);
  std::vector<float> out(W * H * 3);
  std::vector<uint8_t> bytes(out.size() * 4);
  for (uint64_t frame : {1u, 2u}) {
    for (auto& x : out) x = float(frame);
    std::memcpy(bytes.data(), out.data(), bytes.size());
    Result r;
    r.session_id = a->session_id;
    r.frame_index = frame;
    r.planes.push_back({ChannelId::Output, Format::F32, bytes});
    peer.send(r, m->header.request_id);
  }
  if (end == StreamEnd::Closed) peer.send(SessionClosed{a->session_id, 2}, m->header.request_id);
  if (end == StreamEnd::Error)
    peer.send(Error{ErrorCode::UnknownSession, "ATTACH.session_id", "session state lost"}, m->header.request_id);
  if (end == StreamEnd::Hangup) peer.close();
  else peer.recv(2000);
}

class DnWatch : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("dn_watch_cmd_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  std::vector<std::string> args(const std::string& url, std::vector<std::string> extra = {}) {
    std::vector<std::string> a = {"--server", url, "--session", "42", "--key", kKey, "--output",
                                  (dir / "w_%04d.png").string(), "--quiet", "--timeout", "60"};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  }
  fs::path dir;
};

// --count 5 but the session closes after 2: the frames that came are written and the watch ends normally.
TEST_F(DnWatch, SessionClosedIsANormalEnd) {
  FakeServer server([&](Peer& peer) { stream_then_end(peer, StreamEnd::Closed); });
  EXPECT_EQ(cli::run_watch(args(server.url(), {"--count", "5"})), cli::kExitOk);
  server.join();
  EXPECT_TRUE(fs::exists(dir / "w_0002.png"));
}

TEST_F(DnWatch, SessionClosedIsReportedAsAnEndNotAnError) {
  FakeServer server([&](Peer& peer) { stream_then_end(peer, StreamEnd::Closed); });
  auto a = args(server.url());
  a.erase(std::find(a.begin(), a.end(), "--quiet"));
  testing::internal::CaptureStderr();
  const int rc = cli::run_watch(a);
  const std::string err = testing::internal::GetCapturedStderr();
  server.join();
  EXPECT_EQ(rc, cli::kExitOk);
  EXPECT_NE(err.find("dn: session 42 ended normally after 2 frames"), std::string::npos) << err;
  EXPECT_EQ(err.find("error"), std::string::npos) << err;
}

// An ERROR on the stream, or the connection lost, ends the watch with an error, even without --count.
TEST_F(DnWatch, StreamErrorOrLostConnectionIsAnError) {
  FakeServer server([&](Peer& peer) { stream_then_end(peer, StreamEnd::Error); });
  EXPECT_THROW(cli::run_watch(args(server.url())), client::Error);
  server.join();
  FakeServer hangup([&](Peer& peer) { stream_then_end(peer, StreamEnd::Hangup); });
  EXPECT_THROW(cli::run_watch(args(hangup.url())), client::Error);
  hangup.join();
}

}  // namespace
