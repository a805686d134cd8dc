// RESULT.samples (protocol 1.9, docs/protocol.md §5.7) through a real
// dnserver: on a still view frame k of an accumulate session rests on k
// frames, and the owner and a 1.9 watcher get those counts; a 1.8 watcher
// gets the 1.8 payload (decoded strictly as 1.8: a byte more would fail); a
// pipeline without a count says so.
#include <gtest/gtest.h>

#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

using protocol::ChannelId;
using protocol::Format;

RawClient attached_watcher(const ServerProcess& server, const protocol::Session& session, uint8_t minor) {
  RawClient w(server.tcp_url());
  std::vector<uint8_t> hello = protocol::encode(protocol::Hello{0, "watcher", ""}, 1);
  hello[5] = minor;  // header version_minor: the watcher's protocol
  w.send_bytes(hello);
  w.read_as_minor(minor);
  EXPECT_TRUE(w.receive());
  std::vector<uint8_t> attach = protocol::encode(protocol::Attach{session.session_id, session.watch_key}, 2);
  attach[5] = minor;
  w.send_bytes(attach);
  auto attached = w.receive();
  EXPECT_TRUE(attached && std::get_if<protocol::Session>(&attached->message)) << "ATTACH was refused";
  return w;
}

std::optional<protocol::SampleCounts> next_samples(RawClient& c, const char* who) {
  auto r = c.receive();
  EXPECT_TRUE(r) << who << ": no RESULT";
  if (!r) return std::nullopt;
  const auto* result = std::get_if<protocol::Result>(&r->message);
  EXPECT_TRUE(result) << who << ": not a RESULT";
  return result ? result->samples : std::nullopt;
}

}  // namespace

TEST(ResultSamples, EachPeerGetsTheCountsItsProtocolKnows) {
  ServerProcess server;
  RawClient owner(server.tcp_url());
  owner.hello();
  protocol::OpenSession request;
  request.width = 16;
  request.height = 8;
  request.pipeline = "accumulate";
  request.output_format = Format::F32;
  request.channels = {{ChannelId::Radiance, Format::F32},
                      {ChannelId::Normal, Format::F32},
                      {ChannelId::Depth, Format::F32},
                      {ChannelId::Motion, Format::F32}};
  const protocol::Session session = owner.open_session(request);
  RawClient current = attached_watcher(server, session, protocol::kVersionMinor);
  RawClient older = attached_watcher(server, session, protocol::kSamplesMinor - 1);

  for (uint32_t k = 1; k <= 3; ++k) {
    SyntheticFrame f = make_frame(session.session_id, k, 16, 8, request.channels, 2.0f);
    owner.send(f.frame, 10 + k);
    for (auto [c, who] : {std::pair{&owner, "owner"}, std::pair{&current, "1.9 watcher"}}) {
      const auto s = next_samples(*c, who);
      ASSERT_TRUE(s) << who << ", frame " << k;
      EXPECT_TRUE(s->counted) << who;
      EXPECT_EQ(s->min, k) << who;
      EXPECT_EQ(s->median, k) << who;
    }
    std::optional<protocol::SampleCounts> old;
    ASSERT_NO_THROW(old = next_samples(older, "1.8 watcher")) << "the 1.8 watcher got bytes it does not know";
    EXPECT_FALSE(old);
  }

  // passthrough keeps no count: the field is there, not counted.
  const protocol::OpenSession plain = passthrough_session(16, 8);
  const uint64_t id = owner.open(plain, 20);
  SyntheticFrame f = make_frame(id, 0, 16, 8, plain.channels, 1.0f);
  owner.send(f.frame, 21);
  const auto s = next_samples(owner, "passthrough owner");
  ASSERT_TRUE(s);
  EXPECT_FALSE(s->counted);
}

}  // namespace dn::test
