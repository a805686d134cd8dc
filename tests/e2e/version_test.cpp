// Minor versions against a real dnserver (docs/protocol.md §10): after the
// handshake each side sends only what min(client minor, server minor)
// defines. Channel ids 12-14 (the lighting forms) are 1.2: a 1.1 client is
// not offered them and may not declare them; likewise ids 51-54 (the sample
// statistics) and a 1.4 client.
#include <gtest/gtest.h>

#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

using protocol::ChannelId;

constexpr uint64_t kOneTwoChannels = protocol::channel_bit(ChannelId::DiffuseLighting) |
                                     protocol::channel_bit(ChannelId::SpecularLighting) |
                                     protocol::channel_bit(ChannelId::SpecularAlbedo);

// `m` encoded with header minor `minor` (a client of that version).
std::vector<uint8_t> as_minor(const protocol::Message& m, uint64_t request_id, uint8_t minor) {
  std::vector<uint8_t> bytes = protocol::encode(m, request_id);
  bytes[5] = minor;
  return bytes;
}

protocol::Welcome welcome_for(RawClient& c, uint8_t minor) {
  c.read_as_minor(minor);
  c.send_bytes(as_minor(protocol::Hello{0, "v1." + std::to_string(minor), ""}, 1, minor));
  auto r = c.receive();
  if (!r) throw std::runtime_error("no WELCOME");
  return std::get<protocol::Welcome>(r->message);
}

TEST(Versions, OneOneClientIsNotOfferedTheOneTwoChannels) {
  ServerProcess server;
  RawClient old_client(server.tcp_url());
  const protocol::Welcome w11 = welcome_for(old_client, 1);
  RawClient new_client(server.tcp_url());
  const protocol::Welcome w12 = welcome_for(new_client, 2);
  ASSERT_EQ(w11.pipelines.size(), w12.pipelines.size());
  bool any_takes_them = false;
  for (size_t i = 0; i < w12.pipelines.size(); ++i) {
    SCOPED_TRACE(w12.pipelines[i].name);
    EXPECT_EQ((w11.pipelines[i].required_channels | w11.pipelines[i].optional_channels) & kOneTwoChannels, 0u);
    EXPECT_EQ(w11.pipelines[i].optional_channels, w12.pipelines[i].optional_channels & ~kOneTwoChannels);
    any_takes_them = any_takes_them || (w12.pipelines[i].optional_channels & kOneTwoChannels) != 0;
  }
  EXPECT_TRUE(any_takes_them) << "svgf takes the lighting forms from a 1.2 client";
}

TEST(Versions, OneOneClientDeclaringAOneTwoChannelIsRefusedByName) {
  ServerProcess server;
  RawClient c(server.tcp_url());
  welcome_for(c, 1);
  protocol::OpenSession o;
  o.width = 16;
  o.height = 8;
  o.pipeline = "svgf";
  o.output_format = protocol::Format::F32;
  for (ChannelId id : {ChannelId::DiffuseLighting, ChannelId::Specular, ChannelId::Albedo, ChannelId::Normal,
                       ChannelId::Depth, ChannelId::Motion})
    o.channels.push_back({id, protocol::Format::F32});
  c.send_bytes(as_minor(o, 2, 1));
  auto r = c.receive();
  ASSERT_TRUE(r.has_value());
  const auto* e = std::get_if<protocol::Error>(&r->message);
  ASSERT_NE(e, nullptr) << "a SESSION was opened";
  EXPECT_EQ(e->code, protocol::ErrorCode::InvalidChannel);
  EXPECT_EQ(e->field, "OPEN_SESSION.channels[0]");
  EXPECT_NE(e->message.find("'diffuse_lighting' (id 12) is defined from protocol 1.2"), std::string::npos)
      << e->message;
  // The same session from a 1.2 client opens.
  RawClient c12(server.tcp_url());
  welcome_for(c12, 2);
  EXPECT_NO_THROW(c12.open(o, 3));
}

constexpr uint64_t kOneFiveChannels =
    protocol::channel_bit(ChannelId::StatCount) | protocol::channel_bit(ChannelId::StatMean) |
    protocol::channel_bit(ChannelId::StatM2) | protocol::channel_bit(ChannelId::StatM3);

// Ids 51-54, the sample statistics, are 1.5 (docs/protocol.md §7.7): a 1.4
// client sees them in no mask and is not offered a pipeline that requires them.
TEST(Versions, OneFourClientIsNotOfferedTheSampleStatistics) {
  ServerProcess server;
  RawClient old_client(server.tcp_url());
  const protocol::Welcome w14 = welcome_for(old_client, 4);
  RawClient new_client(server.tcp_url());
  const protocol::Welcome w15 = welcome_for(new_client, 5);
  for (const auto& p : w14.pipelines) {
    SCOPED_TRACE(p.name);
    EXPECT_EQ((p.required_channels | p.optional_channels) & kOneFiveChannels, 0u);
  }
  size_t i14 = 0, hidden = 0;
  for (const auto& p : w15.pipelines) {
    SCOPED_TRACE(p.name);
    if (p.required_channels & kOneFiveChannels) {  // not offered to 1.4
      ++hidden;
      continue;
    }
    ASSERT_LT(i14, w14.pipelines.size());
    EXPECT_EQ(w14.pipelines[i14].name, p.name);
    EXPECT_EQ(w14.pipelines[i14].required_channels, p.required_channels);
    EXPECT_EQ(w14.pipelines[i14].optional_channels, p.optional_channels & ~kOneFiveChannels);
    ++i14;
  }
  EXPECT_EQ(i14, w14.pipelines.size());
  EXPECT_GT(hidden, 0u) << "stat requires the statistics: a 1.5 client only";
}

TEST(Versions, OneFourClientDeclaringAStatisticIsRefusedByName) {
  ServerProcess server;
  protocol::OpenSession o;
  o.width = 16;
  o.height = 8;
  o.pipeline = "accumulate";
  o.output_format = protocol::Format::F32;
  o.channels = {{ChannelId::Radiance, protocol::Format::F32}, {ChannelId::StatCount, protocol::Format::F32}};
  auto refusal = [&](uint8_t minor) {
    RawClient c(server.tcp_url());
    welcome_for(c, minor);
    c.send_bytes(as_minor(o, 2, minor));
    auto r = c.receive();
    if (!r) throw std::runtime_error("no reply");
    const auto* e = std::get_if<protocol::Error>(&r->message);
    if (!e) throw std::runtime_error("a SESSION was opened");
    return *e;
  };
  const protocol::Error e14 = refusal(4);
  EXPECT_EQ(e14.code, protocol::ErrorCode::InvalidChannel);
  EXPECT_EQ(e14.field, "OPEN_SESSION.channels[1]");
  EXPECT_NE(e14.message.find("'stat_count' (id 51) is defined from protocol 1.5"), std::string::npos) << e14.message;
  // A 1.5 client may name it, but accumulate does not take it: still refused, for that reason.
  const protocol::Error e15 = refusal(5);
  EXPECT_EQ(e15.code, protocol::ErrorCode::InvalidChannel);
  EXPECT_EQ(e15.field, "OPEN_SESSION.channels[1].id");
  EXPECT_NE(e15.message.find("does not use channel stat_count"), std::string::npos) << e15.message;
}

}  // namespace
}  // namespace dn::test
