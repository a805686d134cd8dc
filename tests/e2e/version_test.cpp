// Minor versions against a real dnserver (docs/protocol.md §10): after the
// handshake each side sends only what min(client minor, server minor)
// defines. Channel ids 12-14 (the lighting forms) are 1.2: a 1.1 client is
// not offered them and may not declare them.
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

}  // namespace
}  // namespace dn::test
