// "auto" through a real dnserver (protocol 1.10, docs/pipelines.md "auto"):
// per channel set the SESSION reply names the pipeline the table chooses and
// why, echoes every declared channel, and frames carrying a channel the
// choice does not read are denoised; a 1.9 client gets the choice without
// the reason field, and WELCOME offers "auto" from 1.10 on.
#include <gtest/gtest.h>

#include <cmath>

#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

using protocol::ChannelId;
using protocol::Format;

protocol::OpenSession auto_session(const std::vector<ChannelId>& ids) {
  protocol::OpenSession request;
  request.width = 32;
  request.height = 16;
  request.pipeline = protocol::kAutoPipeline;
  request.output_format = Format::F32;
  for (ChannelId id : ids) request.channels.push_back({id, Format::F32});
  return request;
}

RawClient client_of_minor(const ServerProcess& server, uint8_t minor, protocol::Welcome* welcome = nullptr) {
  RawClient c(server.tcp_url());
  std::vector<uint8_t> hello = protocol::encode(protocol::Hello{0, "auto-test", ""}, 1);
  hello[5] = minor;
  c.send_bytes(hello);
  c.read_as_minor(minor);
  auto reply = c.receive();
  EXPECT_TRUE(reply && std::get_if<protocol::Welcome>(&reply->message)) << "no WELCOME";
  if (welcome && reply) *welcome = std::get<protocol::Welcome>(reply->message);
  return c;
}

const protocol::PipelineInfo* find(const protocol::Welcome& w, const std::string& name) {
  for (const auto& p : w.pipelines)
    if (p.name == name) return &p;
  return nullptr;
}

struct Expected {
  std::vector<ChannelId> declared;
  const char* pipeline;
  const char* reason_part;  // a part of SESSION.pipeline_reason
};

}  // namespace

TEST(AutoPipeline, EachChannelSetOpensTheTablesPipelineAndRunsItsFrames) {
  ServerProcess server;
  protocol::Welcome welcome;
  RawClient c = client_of_minor(server, protocol::kVersionMinor, &welcome);
  const protocol::PipelineInfo* offered = find(welcome, "auto");
  ASSERT_TRUE(offered) << "WELCOME to a 1.10 client does not offer auto";
  EXPECT_EQ(offered->required_channels, 0u);
  EXPECT_TRUE(offered->parameters.empty());

  const std::vector<Expected> cases = {
      {{ChannelId::Radiance}, "image", "one frame at a time"},
      {{ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal}, "image", "one frame at a time"},
      {{ChannelId::Radiance, ChannelId::Depth, ChannelId::Motion}, "image", "not used: motion"},
      {{ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion}, "svgf",
       "albedo, normal, depth and motion"},
      {{ChannelId::Diffuse, ChannelId::Specular, ChannelId::Albedo, ChannelId::SpecularF0, ChannelId::Roughness,
        ChannelId::Normal, ChannelId::Depth, ChannelId::Motion, ChannelId::Radiance},
       "svgf-fb", "not used: radiance"},
  };
  uint64_t request_id = 10;
  for (const Expected& e : cases) {
    const protocol::OpenSession request = auto_session(e.declared);
    const protocol::Session s = c.open_session(request, ++request_id);
    EXPECT_EQ(s.pipeline, e.pipeline);
    ASSERT_TRUE(s.pipeline_reason) << e.pipeline;
    EXPECT_NE(s.pipeline_reason->find(e.reason_part), std::string::npos) << *s.pipeline_reason;
    ASSERT_EQ(s.channels.size(), request.channels.size()) << "SESSION echoes every declared channel";
    for (size_t i = 0; i < s.channels.size(); ++i) EXPECT_EQ(s.channels[i].id, request.channels[i].id);

    // Every declared plane is sent, the unused ones too; a constant image comes back as itself.
    SyntheticFrame f = make_frame(s.session_id, 0, 32, 16, request.channels, 0.5f);
    c.send(f.frame, ++request_id);
    auto r = c.receive();
    ASSERT_TRUE(r) << e.pipeline << ": no reply to the frame";
    const auto* result = std::get_if<protocol::Result>(&r->message);
    ASSERT_TRUE(result) << e.pipeline << ": " << (std::get_if<protocol::Error>(&r->message)
                                                      ? std::get<protocol::Error>(r->message).message
                                                      : "not a RESULT");
    EXPECT_TRUE(std::isfinite(first_output_value(*result))) << e.pipeline;
  }
}

TEST(AutoPipeline, TheChosenPipelineStillRefusesAFrameWithoutADeclaredPlane) {
  ServerProcess server;
  RawClient c = client_of_minor(server, protocol::kVersionMinor);
  const protocol::OpenSession request = auto_session({ChannelId::Radiance, ChannelId::Motion});
  const protocol::Session s = c.open_session(request, 2);
  EXPECT_EQ(s.pipeline, "image");
  SyntheticFrame f = make_frame(s.session_id, 0, 32, 16, {{ChannelId::Radiance, Format::F32}}, 0.5f);
  c.send(f.frame, 3);
  auto r = c.receive();
  ASSERT_TRUE(r);
  const auto* err = std::get_if<protocol::Error>(&r->message);
  ASSERT_TRUE(err) << "a frame without its declared motion plane was accepted";
  EXPECT_EQ(err->code, protocol::ErrorCode::MissingChannel);
  EXPECT_NE(err->message.find("motion"), std::string::npos) << err->message;
}

TEST(AutoPipeline, AutoWithParametersIsRefusedWithTheFix) {
  ServerProcess server;
  RawClient c = client_of_minor(server, protocol::kVersionMinor);
  protocol::OpenSession request = auto_session({ChannelId::Radiance});
  request.parameters = {{"iterations", 3}};
  c.send(request, 2);
  auto r = c.receive();
  ASSERT_TRUE(r);
  const auto* err = std::get_if<protocol::Error>(&r->message);
  ASSERT_TRUE(err);
  EXPECT_EQ(err->code, protocol::ErrorCode::InvalidParameter);
  EXPECT_EQ(err->field, "OPEN_SESSION.parameters[0].name");
  EXPECT_NE(err->message.find("name the pipeline"), std::string::npos) << err->message;
}

TEST(AutoPipeline, AnOlderClientGetsTheChoiceWithoutTheReason) {
  ServerProcess server;
  const uint8_t older = protocol::kAutoMinor - 1;
  protocol::Welcome welcome;
  RawClient c = client_of_minor(server, older, &welcome);
  EXPECT_FALSE(find(welcome, "auto")) << "WELCOME to a 1.9 client offers auto";
  std::vector<uint8_t> open = protocol::encode(auto_session({ChannelId::Radiance}), 2);
  open[5] = older;
  c.send_bytes(open);
  std::optional<Received> r;
  ASSERT_NO_THROW(r = c.receive()) << "the 1.9 client got bytes it does not know";
  ASSERT_TRUE(r);
  const auto* s = std::get_if<protocol::Session>(&r->message);
  ASSERT_TRUE(s) << "auto refused to a 1.9 client";
  EXPECT_EQ(s->pipeline, "image");
  EXPECT_FALSE(s->pipeline_reason);
}

}  // namespace dn::test
