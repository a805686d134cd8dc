// SHARE_INPUT (protocol 1.7, docs/protocol.md §3.1): the owner's flag at
// OPEN_SESSION makes watchers' RESULT copies carry the frame's noisy radiance
// beside the output; without it, or for a watcher older than 1.7, they carry
// the output alone. Against a real dnserver.
#include <gtest/gtest.h>

#include <cstring>

#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

using protocol::ChannelId;
using protocol::ErrorCode;

// The owner (flag or not), a watcher attached with the key, one frame sent.
struct Watched {
  RawClient owner;
  RawClient watcher;
  SyntheticFrame frame;
};

Watched watch_one_frame(const ServerProcess& server, uint32_t open_flags, uint8_t watcher_minor) {
  Watched w{RawClient(server.tcp_url()), RawClient(server.tcp_url()), {}};
  w.owner.hello();
  const protocol::OpenSession request = passthrough_session(16, 8);
  w.owner.send(request, 1, open_flags);
  auto opened = w.owner.receive();
  EXPECT_TRUE(opened && std::get_if<protocol::Session>(&opened->message)) << "OPEN_SESSION was refused";
  const auto& session = std::get<protocol::Session>(opened->message);

  std::vector<uint8_t> hello = protocol::encode(protocol::Hello{0, "watcher", ""}, 1);
  hello[5] = watcher_minor;  // header version_minor: the watcher's protocol
  w.watcher.send_bytes(hello);
  w.watcher.read_as_minor(watcher_minor);
  EXPECT_TRUE(w.watcher.receive());
  std::vector<uint8_t> attach = protocol::encode(protocol::Attach{session.session_id, session.watch_key}, 2);
  attach[5] = watcher_minor;
  w.watcher.send_bytes(attach);
  auto attached = w.watcher.receive();
  EXPECT_TRUE(attached && std::get_if<protocol::Session>(&attached->message)) << "ATTACH was refused";

  w.frame = make_frame(session.session_id, 0, 16, 8, request.channels, 3.25f);
  w.owner.send(w.frame.frame, 7);
  return w;
}

// The planes of the next RESULT on `c`, by channel id.
std::vector<protocol::PlaneView> result_planes(RawClient& c, Received& keep) {
  auto r = c.receive();
  if (!r) return {};
  keep = std::move(*r);
  auto* result = std::get_if<protocol::Result>(&keep.message);
  return result ? result->planes : std::vector<protocol::PlaneView>{};
}

const protocol::PlaneView* find_plane(const std::vector<protocol::PlaneView>& planes, ChannelId id) {
  for (const auto& p : planes)
    if (p.id == id) return &p;
  return nullptr;
}

std::vector<uint8_t> sent_radiance(const protocol::Frame& f) {
  for (const auto& p : f.planes)
    if (p.id == ChannelId::Radiance) return {p.bytes.begin(), p.bytes.end()};
  return {};
}

}  // namespace

TEST(ShareInput, WatcherGetsTheNoisyRadianceBesideTheOutput) {
  ServerProcess server;
  Watched w = watch_one_frame(server, protocol::kFlagShareInput, protocol::kVersionMinor);
  Received keep_owner, keep_watcher;
  const auto owner_planes = result_planes(w.owner, keep_owner);
  const auto watcher_planes = result_planes(w.watcher, keep_watcher);
  // The owner's own RESULT is unchanged: the output alone.
  ASSERT_EQ(owner_planes.size(), 1u);
  EXPECT_EQ(owner_planes[0].id, ChannelId::Output);
  ASSERT_EQ(watcher_planes.size(), 2u);
  const auto* output = find_plane(watcher_planes, ChannelId::Output);
  const auto* input = find_plane(watcher_planes, ChannelId::Radiance);
  ASSERT_TRUE(output && input);
  EXPECT_TRUE(std::equal(output->bytes.begin(), output->bytes.end(), owner_planes[0].bytes.begin(),
                         owner_planes[0].bytes.end()));
  EXPECT_EQ(std::vector<uint8_t>(input->bytes.begin(), input->bytes.end()), sent_radiance(w.frame.frame))
      << "the shared input is not the radiance the owner sent";
}

TEST(ShareInput, WithoutTheFlagWatchersGetTheOutputAlone) {
  ServerProcess server;
  Watched w = watch_one_frame(server, 0, protocol::kVersionMinor);
  Received keep;
  const auto planes = result_planes(w.watcher, keep);
  ASSERT_EQ(planes.size(), 1u);
  EXPECT_EQ(planes[0].id, ChannelId::Output);
}

TEST(ShareInput, AWatcherOlderThan17GetsTheOutputAlone) {
  ServerProcess server;
  // read_as_minor(6) also makes an extra plane's bytes fail to decode as 1.6 would not
  Watched w = watch_one_frame(server, protocol::kFlagShareInput, protocol::kShareInputMinor - 1);
  Received keep;
  const auto planes = result_planes(w.watcher, keep);
  ASSERT_EQ(planes.size(), 1u);
  EXPECT_EQ(planes[0].id, ChannelId::Output);
}

TEST(ShareInput, RefusedBeforeProtocol17AndWithoutARadianceChannel) {
  ServerProcess server;
  RawClient old_client(server.tcp_url());
  std::vector<uint8_t> hello = protocol::encode(protocol::Hello{0, "v1.6", ""}, 1);
  hello[5] = protocol::kShareInputMinor - 1;
  old_client.send_bytes(hello);
  old_client.read_as_minor(protocol::kShareInputMinor - 1);
  ASSERT_TRUE(old_client.receive());
  old_client.send(passthrough_session(16, 8), 2, protocol::kFlagShareInput);
  auto r = old_client.receive();
  ASSERT_TRUE(r);
  auto* e = std::get_if<protocol::Error>(&r->message);
  ASSERT_NE(e, nullptr) << "a 1.6 connection opened a session with SHARE_INPUT";
  EXPECT_EQ(e->code, ErrorCode::ReservedFlags);
  EXPECT_EQ(e->field, "header.flags");
  EXPECT_NE(e->message.find("speaks 1.6"), std::string::npos) << e->message;

  RawClient c(server.tcp_url());
  c.hello();
  protocol::OpenSession no_radiance = passthrough_session(16, 8);
  for (auto& ch : no_radiance.channels)
    if (ch.id == ChannelId::Radiance) ch.id = ChannelId::DiffuseLighting;
  c.send(no_radiance, 3, protocol::kFlagShareInput);
  auto r2 = c.receive();
  ASSERT_TRUE(r2);
  auto* e2 = std::get_if<protocol::Error>(&r2->message);
  ASSERT_NE(e2, nullptr);
  EXPECT_EQ(e2->code, ErrorCode::MissingChannel);
  EXPECT_NE(e2->message.find("SHARE_INPUT"), std::string::npos) << e2->message;
}

}  // namespace dn::test
