// Capacity figures on a real dnserver (docs/server.md "Capacity"): the free
// memory is the budget minus what SESSION replies said the sessions hold, the
// predicted number of sessions is what opens before LimitExceeded, and a
// pipeline's frame time appears once its frames ran.
#include <gtest/gtest.h>

#include <cmath>

#include "command.hpp"
#include "dn/client/capacity.hpp"
#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

constexpr uint32_t kWidth = 64, kHeight = 36;

protocol::Stats stats_message(RawClient& c) { return protocol::Stats{stats_values(c)}; }

// A passthrough session declaring every channel the pipeline accepts: the
// reference session the STATS memory model describes.
protocol::OpenSession reference_passthrough(const protocol::Welcome& welcome) {
  protocol::OpenSession o = passthrough_session(kWidth, kHeight);
  o.channels.clear();
  for (const auto& p : welcome.pipelines)
    if (p.name == "passthrough")
      for (const protocol::ChannelInfo& c : protocol::kChannels)
        if ((p.required_channels | p.optional_channels) & protocol::channel_bit(c.id))
          o.channels.push_back({c.id, protocol::Format::F32});
  return o;
}

// Device bytes of one reference session, as a default server's model says.
uint64_t model_session_bytes() {
  ServerProcess server({"--no-warm-up"});
  RawClient c(server.tcp_url());
  c.hello();
  return client::capacity(stats_message(c), "passthrough", kWidth, kHeight).session_bytes;
}

TEST(Capacity, FreeMemoryAndPredictedSessionsMatchWhatOpens) {
  const uint64_t session_bytes = model_session_bytes();
  ASSERT_GT(session_bytes, 0u);
  const uint64_t budget = 5 * session_bytes + session_bytes / 2;  // room for 5 sessions and a half
  ServerProcess server({"--no-warm-up", "--max-device-memory", std::to_string(budget), "--max-sessions", "16"});
  RawClient c(server.tcp_url());
  const protocol::OpenSession request = reference_passthrough(c.hello());

  auto st = stats(c);
  EXPECT_EQ(st.at("device_memory_budget_bytes"), double(budget));
  EXPECT_EQ(st.at("device_memory_free_bytes"), double(budget));
  EXPECT_EQ(st.at("max_sessions"), 16.0);

  uint64_t held = 0;
  for (uint64_t i = 0; i < 2; ++i) {
    const protocol::Session s = c.open_session(request, 10 + i);
    EXPECT_EQ(s.device_bytes, session_bytes) << "the model's bytes for the reference session";
    held += s.device_bytes;
  }
  st = stats(c);
  EXPECT_EQ(st.at("device_memory_free_bytes"), double(budget - held));
  EXPECT_EQ(st.at("device_bytes"), double(held));

  const client::Capacity predicted = client::capacity(stats_message(c), "passthrough", kWidth, kHeight);
  EXPECT_EQ(predicted.by_memory, 3u);  // 5.5 - 2 sessions' worth
  EXPECT_EQ(predicted.by_session_limit, 14u);
  EXPECT_EQ(predicted.sessions, 3u);

  std::string out;  // the CLI prints the same number
  ASSERT_EQ(run_command(std::string(DN_DN_PATH) + " capacity --server " + server.tcp_url() +
                            " --pipeline passthrough --size 64x36",
                        out),
            0)
      << out;
  EXPECT_EQ(out, "3\n");
  const std::string dn = std::string(DN_DN_PATH) + " capacity --server " + server.tcp_url();
  EXPECT_EQ(run_command(dn + " --pipeline passthrough --size 64by36", out), 2) << out;
  EXPECT_NE(out.find("--size"), std::string::npos) << out;
  EXPECT_EQ(run_command(dn + " --pipeline nope --size 64x36", out), 1) << out;
  EXPECT_NE(out.find("pipeline.nope.device_bytes_fixed"), std::string::npos) << out;

  uint64_t opened = 0;
  for (uint64_t i = 0; i < 16; ++i) {
    c.send(request, 100 + i);
    const auto reply = c.receive();
    ASSERT_TRUE(reply);
    if (const auto* e = std::get_if<protocol::Error>(&reply->message)) {
      EXPECT_EQ(e->code, protocol::ErrorCode::LimitExceeded);
      EXPECT_NE(e->message.find("--max-device-memory"), std::string::npos) << e->message;
      break;
    }
    ASSERT_TRUE(std::holds_alternative<protocol::Session>(reply->message));
    ++opened;
  }
  EXPECT_EQ(opened, predicted.sessions);
  EXPECT_EQ(client::capacity(stats_message(c), "passthrough", kWidth, kHeight).sessions, 0u);
}

TEST(Capacity, FrameTimeAppearsOnceFramesRan) {
  ServerProcess server({"--no-warm-up"});
  RawClient c(server.tcp_url());
  const protocol::OpenSession request = reference_passthrough(c.hello());
  auto st = stats(c);
  EXPECT_EQ(st.count("pipeline.passthrough.frame_ms_per_megapixel"), 0u) << "absent until measured";
  EXPECT_EQ(st.at("device_busy_fraction"), 0.0);

  const uint64_t sid = c.open(request);
  for (uint64_t i = 0; i < 3; ++i) {
    auto f = make_frame(sid, i, kWidth, kHeight, request.channels, 0.5f);
    c.send(f.frame, 20 + i);
    const auto r = c.receive();
    ASSERT_TRUE(r && std::holds_alternative<protocol::Result>(r->message));
  }
  st = stats(c);
  ASSERT_EQ(st.count("pipeline.passthrough.frame_ms_per_megapixel"), 1u);
  EXPECT_GT(st.at("pipeline.passthrough.frame_ms_per_megapixel"), 0.0);
  EXPECT_EQ(st.at("pipeline.passthrough.frames_measured"), 3.0);
  EXPECT_EQ(st.count("pipeline.svgf.frame_ms_per_megapixel"), 0u) << "no svgf frame ran";
  EXPECT_GE(st.at("device_busy_fraction"), 0.0);

  const client::Capacity c30 = client::capacity(stats_message(c), "passthrough", kWidth, kHeight, 30);
  ASSERT_TRUE(c30.frame_ms && c30.by_time);
  EXPECT_NEAR(*c30.frame_ms, st.at("pipeline.passthrough.frame_ms_per_megapixel") * kWidth * kHeight / 1e6, 1e-12);
}

}  // namespace
}  // namespace dn::test
