// dn::client against a scripted fake server.
#include <gtest/gtest.h>
#include <sys/socket.h>

#include <cstdlib>
#include <cstring>
#include <fstream>

#include "dn/client/client.hpp"
#include "dn/protocol/codec.hpp"
#include "fake_server.hpp"

namespace {

using namespace dn;
using namespace dn::protocol;
using dn::test::FakeServer;
using dn::test::Peer;
using dn::test::Received;

constexpr uint32_t W = 4, H = 3;
constexpr const char* kKey = "00112233445566778899aabbccddeeff";  // a well-formed watch key (protocol 1.6)

client::ConnectOptions opts(std::optional<std::string> token = std::nullopt) {
  client::ConnectOptions o;
  o.client_name = "client-test";
  o.auth_token = token ? token : std::optional<std::string>("");
  o.connect_timeout = std::chrono::milliseconds(5000);
  o.io_timeout = std::chrono::milliseconds(5000);
  return o;
}

// Answers OPEN_SESSION with a SESSION that echoes the request.
OpenSession serve_open(Peer& peer, uint64_t session_id = 7) {
  auto m = peer.recv();
  EXPECT_TRUE(m.has_value());
  if (!m) return {};
  auto* o = std::get_if<OpenSession>(&m->message);
  EXPECT_NE(o, nullptr) << "expected OPEN_SESSION";
  if (!o) return {};
  Session s;
  s.session_id = session_id;
  s.width = o->width;
  s.height = o->height;
  s.pipeline = o->pipeline;
  s.output_format = o->output_format;
  s.device_bytes = 12345;
  s.channels = o->channels;
  s.watch_key = kKey;
  s.watch_url = "";  // a 1.8 server's SESSION ends with the watch URL
  peer.send(s, m->header.request_id);
  return *o;
}

client::SessionDesc desc() {
  client::SessionDesc d;
  d.width = W;
  d.height = H;
  d.pipeline = "svgf";
  d.channel(ChannelId::Radiance, Format::F32).channel(ChannelId::Albedo, Format::F16);
  return d;
}

const PlaneView* find_plane(const Frame& f, ChannelId id) {
  for (const auto& p : f.planes)
    if (p.id == id) return &p;
  return nullptr;
}

std::vector<float> as_floats(std::span<const uint8_t> bytes) {
  std::vector<float> v(bytes.size() / 4);
  std::memcpy(v.data(), bytes.data(), v.size() * 4);
  return v;
}

// RESULT whose output is 2 * radiance (F32), keeping the payload alive in `keep`.
Result make_result(const Frame& f, std::vector<uint8_t>& keep) {
  Result r;
  r.session_id = f.info.session_id;
  r.frame_index = f.info.frame_index;
  r.timings = {{"upload", 0.25}, {"atrous", 1.5}};
  const PlaneView* rad = find_plane(f, ChannelId::Radiance);
  std::vector<float> out = rad ? as_floats(rad->bytes) : std::vector<float>(W * H * 3, 0.0f);
  for (float& x : out) x *= 2.0f;
  keep.resize(out.size() * 4);
  std::memcpy(keep.data(), out.data(), keep.size());
  r.planes.push_back({ChannelId::Output, Format::F32, keep});
  return r;
}

struct TestFrame {
  std::vector<float> radiance = std::vector<float>(W * H * 3);
  std::vector<float> albedo = std::vector<float>(W * H * 3, 0.5f);
  client::FrameInput input;
  explicit TestFrame(float value) {
    for (size_t i = 0; i < radiance.size(); ++i) radiance[i] = value + 0.001f * float(i);
    input.add(ChannelId::Radiance, radiance);
    input.add(ChannelId::Albedo, albedo);  // f32 given, f16 declared: converted by the client
  }
};

TEST(ClientHandshake, SendsNameAndTokenAndReadsWelcome) {
  std::string seen_name, seen_token;
  FakeServer server([&](Peer& peer) {
    Hello h = peer.handshake(std::string("s3cret"));
    seen_name = h.client_name;
    seen_token = h.auth_token;
    auto m = peer.recv();
    ASSERT_TRUE(m);
    auto* ping = std::get_if<Ping>(&m->message);
    ASSERT_NE(ping, nullptr);
    peer.send(Pong{ping->payload}, m->header.request_id);
    peer.recv(2000);  // until the client hangs up
  });
  auto conn = client::Connection::connect(server.url(), opts("s3cret"));
  EXPECT_EQ(conn.welcome().device_name, "Fake Device");
  EXPECT_EQ(conn.welcome().limits.max_frames_in_flight, 4u);
  ASSERT_NE(conn.find_pipeline("svgf"), nullptr);
  EXPECT_EQ(conn.find_pipeline("nope"), nullptr);
  EXPECT_GE(conn.ping().count(), 0.0);
  conn.close();
  server.join();
  EXPECT_EQ(seen_name, "client-test");
  EXPECT_EQ(seen_token, "s3cret");
}

TEST(ClientHandshake, OverTcpLoopback) {
  FakeServer server(
      [&](Peer& peer) {
        peer.handshake();
        peer.recv(2000);
      },
      /*tcp=*/true);
  ASSERT_EQ(server.url().rfind("tcp://127.0.0.1:", 0), 0u);
  auto conn = client::Connection::connect(server.url(), opts());
  EXPECT_EQ(conn.welcome().server_version, "fake-dnserver 0.0");
  EXPECT_TRUE(conn.is_open());
}

TEST(ClientHandshake, TokenFromEnvironmentAndFile) {
  ::setenv("DN_TOKEN", "from-env", 1);
  client::ConnectOptions o;
  EXPECT_EQ(client::resolve_auth_token(o), "from-env");
  const std::string path = "/tmp/dn_client_test_token_" + std::to_string(::getpid());
  std::ofstream(path) << "  from-file  \n second line ignored\n";
  o.token_file = path;
  EXPECT_EQ(client::resolve_auth_token(o), "from-file");
  o.auth_token = "explicit";
  EXPECT_EQ(client::resolve_auth_token(o), "explicit");
  ::unsetenv("DN_TOKEN");
  ::setenv("DN_TOKEN_FILE", path.c_str(), 1);
  EXPECT_EQ(client::resolve_auth_token(client::ConnectOptions{}), "from-file");
  ::unsetenv("DN_TOKEN_FILE");
  EXPECT_EQ(client::resolve_auth_token(client::ConnectOptions{}), "");
  client::ConnectOptions missing;
  missing.token_file = path + ".missing";
  EXPECT_THROW(client::resolve_auth_token(missing), client::Error);
  std::remove(path.c_str());

  // And the resolved token is what HELLO carries.
  std::string seen;
  FakeServer server([&](Peer& peer) {
    seen = peer.handshake().auth_token;
    peer.recv(2000);
  });
  ::setenv("DN_TOKEN", "env-token", 1);
  client::ConnectOptions env_opts;
  auto conn = client::Connection::connect(server.url(), env_opts);
  ::unsetenv("DN_TOKEN");
  conn.close();
  server.join();
  EXPECT_EQ(seen, "env-token");
}

TEST(ClientHandshake, RejectedTokenIsServerError) {
  FakeServer server([&](Peer& peer) { peer.handshake(std::string("right")); });
  try {
    client::Connection::connect(server.url(), opts("wrong"));
    FAIL() << "connect should throw";
  } catch (const client::Error& e) {
    EXPECT_EQ(e.kind(), client::ErrorKind::Server);
    EXPECT_EQ(e.code(), ErrorCode::Unauthenticated);
    EXPECT_EQ(e.field(), "HELLO.auth_token");
    EXPECT_STREQ(e.what(), "server error Unauthenticated at HELLO.auth_token: bad token");
  }
}

TEST(ClientHandshake, NoServerIsTransportErrorNamingEndpoint) {
  try {
    client::Connection::connect("unix:///tmp/dn_client_test_nobody_listens.sock", opts());
    FAIL() << "connect should throw";
  } catch (const client::Error& e) {
    EXPECT_EQ(e.kind(), client::ErrorKind::Transport);
    EXPECT_NE(std::string(e.what()).find("unix:///tmp/dn_client_test_nobody_listens.sock"), std::string::npos)
        << e.what();
  }
}

TEST(ClientSession, DenoiseRoundTrip) {
  Frame seen{};
  uint32_t seen_flags = 0;
  std::vector<uint8_t> albedo_bytes;
  OpenSession open_seen;
  FakeServer server([&](Peer& peer) {
    peer.handshake();
    open_seen = serve_open(peer);
    auto m = peer.recv();
    ASSERT_TRUE(m);
    auto* f = std::get_if<Frame>(&m->message);
    ASSERT_NE(f, nullptr);
    seen = *f;
    seen_flags = m->header.flags;
    if (auto* a = find_plane(*f, ChannelId::Albedo)) albedo_bytes.assign(a->bytes.begin(), a->bytes.end());
    std::vector<uint8_t> keep;
    peer.send(make_result(*f, keep), m->header.request_id);
    peer.recv(2000);
  });
  auto conn = client::Connection::connect(server.url(), opts());
  client::Session session = conn.open_session(desc().parameter("alpha", 0.1));
  EXPECT_EQ(session.id(), 7u);
  EXPECT_EQ(session.max_in_flight(), 4u);  // from WELCOME

  TestFrame tf(1.0f);
  tf.input.info.view[0] = tf.input.info.view[5] = tf.input.info.view[10] = tf.input.info.view[15] = 2.0f;
  tf.input.info.jitter = {0.25f, -0.25f};
  client::Result r = session.denoise(tf.input);
  EXPECT_EQ(r.frame_index, 0u);
  EXPECT_EQ(r.session_id, 7u);
  ASSERT_TRUE(r.has_output());
  EXPECT_EQ(r.format, Format::F32);
  const std::vector<float> rgb = r.rgb();
  ASSERT_EQ(rgb.size(), size_t(W * H * 3));
  for (size_t i = 0; i < rgb.size(); ++i) EXPECT_FLOAT_EQ(rgb[i], 2.0f * tf.radiance[i]);
  EXPECT_DOUBLE_EQ(r.total_timing_ms(), 1.75);
  EXPECT_EQ(r.timing_ms("atrous"), 1.5);
  EXPECT_GT(r.latency.count(), 0.0);
  conn.close();
  server.join();

  EXPECT_EQ(open_seen.pipeline, "svgf");
  ASSERT_EQ(open_seen.parameters.size(), 1u);
  EXPECT_EQ(open_seen.parameters[0].name, "alpha");
  EXPECT_EQ(seen.info.session_id, 7u);
  EXPECT_EQ(seen_flags, 0u);
  // First frame: previous camera = current camera.
  EXPECT_EQ(seen.info.prev_view, seen.info.view);
  EXPECT_EQ(seen.info.view[0], 2.0f);
  EXPECT_EQ(seen.info.prev_jitter, (std::array<float, 2>{0.25f, -0.25f}));
  // Albedo declared f16, given f32: converted by the client.
  ASSERT_EQ(albedo_bytes.size(), size_t(W * H * 3 * 2));
  uint16_t h0;
  std::memcpy(&h0, albedo_bytes.data(), 2);
  EXPECT_EQ(half_to_float(h0), 0.5f);
}

TEST(ClientSession, PipelinedEightFramesWindowThreeInOrder) {
  size_t max_unanswered = 0;
  std::vector<uint64_t> indices_seen;
  FakeServer server([&](Peer& peer) {
    peer.handshake(std::nullopt, /*max_in_flight=*/8);
    serve_open(peer);
    // Hold frames until the client's window must be full, check that no
    // further frame arrives while it is, then answer the oldest.
    std::deque<Received> held;
    size_t answered = 0;
    while (answered < 8) {
      const size_t need = std::min<size_t>(3, 8 - answered);
      while (held.size() < need) {
        auto m = peer.recv(10000);
        ASSERT_TRUE(m) << "client stalled with " << held.size() << " frames held";
        auto* f = std::get_if<Frame>(&m->message);
        ASSERT_NE(f, nullptr);
        indices_seen.push_back(f->info.frame_index);
        held.push_back(std::move(*m));
      }
      if (auto extra = peer.recv(100)) {  // a 4th frame would break the window
        indices_seen.push_back(std::get<Frame>(extra->message).info.frame_index);
        held.push_back(std::move(*extra));
      }
      max_unanswered = std::max(max_unanswered, held.size());
      std::vector<uint8_t> keep;
      const Frame& f = std::get<Frame>(held.front().message);
      peer.send(make_result(f, keep), held.front().header.request_id);
      held.pop_front();
      ++answered;
    }
    peer.recv(2000);
  });
  auto conn = client::Connection::connect(server.url(), opts());
  client::SessionDesc d = desc();
  d.max_in_flight = 3;
  client::Session session = conn.open_session(d);
  EXPECT_EQ(session.max_in_flight(), 3u);

  std::vector<std::unique_ptr<TestFrame>> frames;
  std::vector<client::Result> results;
  for (int i = 0; i < 8; ++i) {
    frames.push_back(std::make_unique<TestFrame>(float(i)));
    frames.back()->input.frame_index = 10 + uint64_t(i) * 2;
    EXPECT_EQ(session.submit(frames.back()->input), 10 + uint64_t(i) * 2);
    EXPECT_LE(session.in_flight(), 8u);
  }
  while (session.in_flight() > 0) results.push_back(session.wait());
  conn.close();
  server.join();

  EXPECT_EQ(max_unanswered, 3u);
  ASSERT_EQ(results.size(), 8u);
  for (int i = 0; i < 8; ++i) {
    EXPECT_EQ(results[size_t(i)].frame_index, 10 + uint64_t(i) * 2);
    EXPECT_FLOAT_EQ(results[size_t(i)].rgb()[0], 2.0f * float(i)) << "frame " << i;
  }
  ASSERT_EQ(indices_seen.size(), 8u);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(indices_seen[size_t(i)], 10 + uint64_t(i) * 2);
}

TEST(ClientSession, ServerErrorSurfacesWithCodeAndFieldAndSessionStaysUsable) {
  FakeServer server([&](Peer& peer) {
    peer.handshake();
    serve_open(peer);
    auto m = peer.recv();
    ASSERT_TRUE(m);
    peer.send(Error{ErrorCode::InvalidChannel, "FRAME.planes[1]", "albedo has NaNs"}, m->header.request_id);
    m = peer.recv();
    ASSERT_TRUE(m);
    std::vector<uint8_t> keep;
    peer.send(make_result(std::get<Frame>(m->message), keep), m->header.request_id);
    peer.recv(2000);
  });
  auto conn = client::Connection::connect(server.url(), opts());
  client::Session session = conn.open_session(desc());
  TestFrame a(1.0f), b(2.0f);
  try {
    session.denoise(a.input);
    FAIL() << "expected a server error";
  } catch (const client::Error& e) {
    EXPECT_EQ(e.kind(), client::ErrorKind::Server);
    EXPECT_EQ(e.code(), ErrorCode::InvalidChannel);
    EXPECT_EQ(e.field(), "FRAME.planes[1]");
    EXPECT_EQ(e.server_message(), "albedo has NaNs");
    EXPECT_STREQ(e.what(), "server error InvalidChannel at FRAME.planes[1]: albedo has NaNs");
  }
  client::Result r = session.denoise(b.input);
  EXPECT_EQ(r.frame_index, 1u);
  EXPECT_FLOAT_EQ(r.rgb()[0], 4.0f);
}

TEST(ClientSession, ServerClosingMidFrameIsTransportError) {
  FakeServer server([&](Peer& peer) {
    peer.handshake();
    serve_open(peer);
    // Read the header and a little of the FRAME, then hang up.
    peer.read_raw(kHeaderSize + 64);
    peer.close();
  });
  auto conn = client::Connection::connect(server.url(), opts());
  client::SessionDesc d;
  d.width = 512;
  d.height = 512;  // 3 MiB of radiance: larger than the socket buffers
  d.pipeline = "svgf";
  d.channel(ChannelId::Radiance);
  client::Session session = conn.open_session(d);
  std::vector<float> big(size_t(512) * 512 * 3, 1.0f);
  client::FrameInput in;
  in.add(ChannelId::Radiance, big);
  try {
    session.denoise(in);
    FAIL() << "expected a transport error";
  } catch (const client::Error& e) {
    EXPECT_EQ(e.kind(), client::ErrorKind::Transport) << e.what();
    EXPECT_EQ(e.endpoint(), server.url());
    EXPECT_NE(std::string(e.what()).find(server.url()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(conn.is_open());
  EXPECT_THROW(conn.ping(), client::Error);
}

TEST(ClientSession, ServerDroppingConnectionWhileWaitingIsTransportError) {
  FakeServer server([&](Peer& peer) {
    peer.handshake();
    serve_open(peer);
    ASSERT_TRUE(peer.recv());  // the whole frame
    peer.close();
  });
  auto conn = client::Connection::connect(server.url(), opts());
  client::Session session = conn.open_session(desc());
  TestFrame f(1.0f);
  try {
    session.denoise(f.input);
    FAIL() << "expected a transport error";
  } catch (const client::Error& e) {
    EXPECT_EQ(e.kind(), client::ErrorKind::Transport);
    EXPECT_NE(std::string(e.what()).find("connection lost: the server closed the connection"), std::string::npos) << e.what();
  }
}

TEST(ClientSession, LocalChecksRejectBadPlanesBeforeSending) {
  std::vector<MessageType> types_seen;
  FakeServer server([&](Peer& peer) {
    peer.handshake();
    serve_open(peer);
    for (;;) {
      auto m = peer.recv(3000);
      if (!m) break;
      types_seen.push_back(type_of(m->message));
      if (auto* p = std::get_if<Ping>(&m->message)) peer.send(Pong{p->payload}, m->header.request_id);
    }
  });
  auto conn = client::Connection::connect(server.url(), opts());
  client::Session session = conn.open_session(desc());

  std::vector<float> radiance(W * H * 3, 1.0f), short_albedo(W * H * 3 - 3, 1.0f), normal(W * H * 3, 0.0f);
  client::FrameInput wrong_size;
  wrong_size.add(ChannelId::Radiance, radiance).add(ChannelId::Albedo, short_albedo);
  try {
    session.submit(wrong_size);
    FAIL() << "expected a local size error";
  } catch (const client::Error& e) {
    EXPECT_EQ(e.kind(), client::ErrorKind::Usage);
    EXPECT_EQ(e.code(), ErrorCode::InvalidChannel);
    EXPECT_EQ(e.field(), "FRAME.planes[1].byte_length");
    EXPECT_NE(std::string(e.what()).find("'albedo'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("expects 144"), std::string::npos) << e.what();
  }
  client::FrameInput undeclared;
  undeclared.add(ChannelId::Radiance, radiance).add(ChannelId::Normal, normal);
  try {
    session.submit(undeclared);
    FAIL() << "expected an undeclared-channel error";
  } catch (const client::Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidChannel);
    EXPECT_NE(std::string(e.what()).find("'normal' was not declared"), std::string::npos) << e.what();
  }
  client::FrameInput twice;
  twice.add(ChannelId::Radiance, radiance).add(ChannelId::Radiance, radiance);
  EXPECT_THROW(session.submit(twice), client::Error);
  EXPECT_EQ(session.in_flight(), 0u);
  conn.ping();  // the server has seen everything sent before it
  conn.close();
  server.join();
  EXPECT_EQ(types_seen, std::vector<MessageType>{MessageType::Ping});
}

TEST(ClientSession, FrameLargerThanServerLimitIsRejectedLocally) {
  std::vector<MessageType> types_seen;
  FakeServer server([&](Peer& peer) {
    peer.handshake(std::nullopt, 4, /*max_message_bytes=*/1 << 20);
    serve_open(peer);
    for (;;) {
      auto m = peer.recv(3000);
      if (!m) break;
      types_seen.push_back(type_of(m->message));
      if (auto* p = std::get_if<Ping>(&m->message)) peer.send(Pong{p->payload}, m->header.request_id);
    }
  });
  auto conn = client::Connection::connect(server.url(), opts());
  client::SessionDesc d;
  d.width = 512;
  d.height = 512;
  d.pipeline = "svgf";
  d.channel(ChannelId::Radiance);
  client::Session session = conn.open_session(d);
  std::vector<float> big(size_t(512) * 512 * 3, 1.0f);
  client::FrameInput in;
  in.add(ChannelId::Radiance, big);
  try {
    session.submit(in);
    FAIL();
  } catch (const client::Error& e) {
    EXPECT_EQ(e.kind(), client::ErrorKind::Usage);
    EXPECT_EQ(e.code(), ErrorCode::LimitExceeded);
    EXPECT_NE(std::string(e.what()).find("1048576"), std::string::npos) << e.what();
  }
  EXPECT_EQ(session.in_flight(), 0u);
  conn.ping();
  conn.close();
  server.join();
  EXPECT_EQ(types_seen, std::vector<MessageType>{MessageType::Ping});
}

TEST(ClientSession, FrameIndexMustIncrease) {
  FakeServer server([&](Peer& peer) {
    peer.handshake();
    serve_open(peer);
    auto m = peer.recv();
    ASSERT_TRUE(m);
    std::vector<uint8_t> keep;
    peer.send(make_result(std::get<Frame>(m->message), keep), m->header.request_id);
    peer.recv(2000);
  });
  auto conn = client::Connection::connect(server.url(), opts());
  client::Session session = conn.open_session(desc());
  TestFrame f(1.0f);
  f.input.frame_index = 5;
  session.denoise(f.input);
  try {
    session.submit(f.input);
    FAIL();
  } catch (const client::Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::OutOfOrder);
  }
}

TEST(ClientSession, NoOutputFlagAndCloseAndStats) {
  uint32_t flags = 0;
  FakeServer server([&](Peer& peer) {
    peer.handshake();
    serve_open(peer, 9);
    auto m = peer.recv();
    ASSERT_TRUE(m);
    flags = m->header.flags;
    Result r;
    r.session_id = 9;
    r.frame_index = std::get<Frame>(m->message).info.frame_index;
    peer.send(r, m->header.request_id);
    m = peer.recv();
    ASSERT_TRUE(m);
    ASSERT_TRUE(std::holds_alternative<StatsRequest>(m->message));
    peer.send(Stats{{{"sessions", 1.0}, {"frames", 1.0}}}, m->header.request_id);
    m = peer.recv();
    ASSERT_TRUE(m);
    auto* c = std::get_if<CloseSession>(&m->message);
    ASSERT_NE(c, nullptr);
    EXPECT_EQ(c->session_id, 9u);
    peer.send(SessionClosed{9, 1}, m->header.request_id);
    peer.recv(2000);
  });
  auto conn = client::Connection::connect(server.url(), opts());
  client::Session session = conn.open_session(desc());
  TestFrame f(1.0f);
  f.input.no_output = true;
  client::Result r = session.denoise(f.input);
  EXPECT_FALSE(r.has_output());
  EXPECT_THROW(r.rgb(), client::Error);
  const Stats s = conn.stats();
  ASSERT_EQ(s.values.size(), 2u);
  EXPECT_EQ(s.values[0].name, "sessions");
  const SessionClosed closed = session.close();
  EXPECT_EQ(closed.frames_processed, 1u);
  EXPECT_FALSE(session.is_open());
  EXPECT_THROW(session.submit(f.input), client::Error);
  conn.close();
  server.join();
  EXPECT_EQ(flags, kFlagNoOutput);
}

TEST(ClientSession, ReplyTimeoutIsTransportTimeout) {
  FakeServer server([&](Peer& peer) {
    peer.handshake();
    peer.recv(3000);  // the PING, never answered
    peer.recv(3000);
  });
  client::ConnectOptions o = opts();
  o.io_timeout = std::chrono::milliseconds(200);
  auto conn = client::Connection::connect(server.url(), o);
  try {
    conn.ping();
    FAIL();
  } catch (const client::Error& e) {
    EXPECT_TRUE(e.is_timeout()) << e.what();
    EXPECT_NE(std::string(e.what()).find("PING"), std::string::npos) << e.what();
  }
}

TEST(ClientWatcher, NextReturnsNewestAndEndsWithSession) {
  FakeServer server([&](Peer& peer) {
    peer.handshake_with(dn::test::test_welcome_with_parameters());  // a server of this version: keys
    auto m = peer.recv();
    ASSERT_TRUE(m);
    auto* a = std::get_if<Attach>(&m->message);
    ASSERT_NE(a, nullptr);
    EXPECT_EQ(a->watch_key, std::optional<std::string>(kKey)) << "ATTACH carries the key given to attach()";
    Session s;
    s.watch_key = "";  // the reply to ATTACH does not repeat it
    s.watch_url = "";  // a 1.8 server's SESSION ends with the watch URL
    s.pipeline_reason = "";  // ... a 1.10 server's with the reason for an auto choice
    s.session_id = a->session_id;
    s.width = W;
    s.height = H;
    s.pipeline = "svgf";
    s.read_only = true;
    // SESSION and three RESULTs in one write: they arrive together.
    std::vector<uint8_t> burst = encode(s, m->header.request_id);
    std::vector<float> out(W * H * 3);
    std::vector<uint8_t> bytes(out.size() * 4);
    for (uint64_t frame : {5u, 6u, 7u}) {
      for (auto& x : out) x = float(frame);
      std::memcpy(bytes.data(), out.data(), bytes.size());
      Result r;
      r.session_id = a->session_id;
      r.frame_index = frame;
      r.planes.push_back({ChannelId::Output, Format::F32, bytes});
      r.samples = protocol::SampleCounts{true, 1, uint32_t(frame)};  // a 1.9 server's RESULT ends with the counts
      // The stream may carry the ATTACH request id or 0: both reach the watcher.
      encode(r, frame == 6 ? 0 : m->header.request_id, 0, burst);
    }
    peer.send_raw(burst);
    // The client pings once it has seen the first three.
    auto ping = peer.recv();
    ASSERT_TRUE(ping);
    ASSERT_TRUE(std::holds_alternative<Ping>(ping->message));
    peer.send(Pong{std::get<Ping>(ping->message).payload}, ping->header.request_id);
    for (auto& x : out) x = 8.0f;
    std::memcpy(bytes.data(), out.data(), bytes.size());
    Result r;
    r.session_id = a->session_id;
    r.frame_index = 8;
    r.planes.push_back({ChannelId::Output, Format::F32, bytes});
    peer.send(r, m->header.request_id);
    peer.send(SessionClosed{a->session_id, 9}, m->header.request_id);
    peer.recv(2000);
  });
  auto conn = client::Connection::connect(server.url(), opts());
  EXPECT_EQ(conn.protocol_minor(), kVersionMinor);
  client::Watcher w = conn.attach(42, kKey);
  EXPECT_TRUE(w.info().read_only);
  EXPECT_EQ(w.session_id(), 42u);
  client::Result r = w.next();
  EXPECT_EQ(r.frame_index, 7u);
  EXPECT_EQ(w.dropped(), 2u);
  EXPECT_FLOAT_EQ(r.rgb()[0], 7.0f);
  ASSERT_TRUE(r.samples);
  EXPECT_EQ(r.samples->min, 1u);
  EXPECT_EQ(r.samples->median, 7u);
  conn.ping();
  client::Result r8 = w.next();
  EXPECT_EQ(r8.frame_index, 8u);
  EXPECT_FALSE(r8.samples) << "a RESULT whose pipeline counts nothing has no samples";
  try {
    w.next();
    FAIL() << "the session ended";
  } catch (const client::Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::UnknownSession);
  }
}

TEST(ClientWatcher, AttachToUnknownSessionThrows) {
  FakeServer server([&](Peer& peer) {
    peer.handshake();  // a 1.0 server: it knows no watch key, so none is sent
    auto m = peer.recv();
    ASSERT_TRUE(m);
    auto* a = std::get_if<Attach>(&m->message);
    ASSERT_NE(a, nullptr);
    EXPECT_FALSE(a->watch_key.has_value());
    EXPECT_EQ(m->header.payload_length, 8u);
    peer.send(Error{ErrorCode::UnknownSession, "ATTACH.session_id", "no session 3"}, m->header.request_id);
    peer.recv(2000);
  });
  auto conn = client::Connection::connect(server.url(), opts());
  EXPECT_EQ(conn.protocol_minor(), 0);
  try {
    conn.attach(3, kKey);
    FAIL();
  } catch (const client::Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::UnknownSession);
    EXPECT_EQ(e.field(), "ATTACH.session_id");
  }
}

TEST(ClientWatcher, MalformedWatchKeyIsRefusedBeforeSending) {
  bool got_attach = false;
  FakeServer server([&](Peer& peer) {
    peer.handshake_with(dn::test::test_welcome_with_parameters());
    auto m = peer.recv(1000);
    got_attach = m && std::holds_alternative<Attach>(m->message);
  });
  auto conn = client::Connection::connect(server.url(), opts());
  for (const char* bad : {"", "00112233445566778899AABBCCDDEEFF", "0011", "00112233445566778899aabbccddeeff0"}) {
    try {
      conn.attach(42, bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const client::Error& e) {
      EXPECT_EQ(e.kind(), client::ErrorKind::Usage) << bad;
      EXPECT_EQ(e.field(), "ATTACH.watch_key") << bad;
      EXPECT_NE(std::string(e.what()).find("32 lowercase hex digits"), std::string::npos) << e.what();
    }
  }
  conn.close();
  server.join();
  EXPECT_FALSE(got_attach) << "a malformed key was sent";
}

}  // namespace
