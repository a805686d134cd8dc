// Misbehaving clients against a real dnserver process on loopback: each gets
// its clear ERROR or a clean close, and a well-behaved renderer streaming at
// the same time loses and reorders nothing.
#include <gtest/gtest.h>

#include <cstring>

#include "raw_client.hpp"
#include "server_process.hpp"
#include "well_behaved.hpp"

namespace dn::test {
namespace {

using protocol::ErrorCode;

class BadInput : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { server_ = new ServerProcess({"--max-message", "64M"}); }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
  }
  void SetUp() override { good_ = std::make_unique<WellBehavedClient>(server_->tcp_url(), 40); }
  void TearDown() override {
    EXPECT_EQ(good_->join(), "") << "the well-behaved client was disturbed";
    EXPECT_EQ(good_->results_received(), 40);
    EXPECT_TRUE(server_->running());
  }

  // Sends raw bytes on a fresh connection and expects ERROR(code) then a close.
  void expect_fatal(const std::vector<uint8_t>& bytes, ErrorCode code, const std::string& field_part) {
    RawClient c(server_->tcp_url());
    c.send_bytes(bytes);
    auto r = c.receive(10.0);
    ASSERT_TRUE(r) << "no ERROR before the close";
    auto* e = std::get_if<protocol::Error>(&r->message);
    ASSERT_NE(e, nullptr) << "expected ERROR, got " << protocol::to_string(r->header.type);
    EXPECT_EQ(e->code, code) << e->message;
    EXPECT_NE(e->field.find(field_part), std::string::npos) << "field '" << e->field << "'";
    EXPECT_FALSE(e->message.empty());
    EXPECT_TRUE(c.closed_by_server());
  }

  static std::vector<uint8_t> hello_bytes() { return protocol::encode(protocol::Hello{0, "t", ""}, 7); }

  static ServerProcess* server_;
  std::unique_ptr<WellBehavedClient> good_;
};
ServerProcess* BadInput::server_ = nullptr;

void put_u32(std::vector<uint8_t>& b, size_t at, uint32_t v) { std::memcpy(b.data() + at, &v, 4); }

TEST_F(BadInput, GarbageBytesGetBadMagic) {
  std::vector<uint8_t> garbage(100);
  for (size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<uint8_t>(i * 37 + 11);
  expect_fatal(garbage, ErrorCode::BadMagic, "magic");
}

TEST_F(BadInput, WrongMagic) {
  auto b = hello_bytes();
  b[0] = 'X';
  expect_fatal(b, ErrorCode::BadMagic, "magic");
}

TEST_F(BadInput, UnsupportedMajorVersion) {
  auto b = hello_bytes();
  b[4] = 2;
  expect_fatal(b, ErrorCode::UnsupportedVersion, "version");
}

TEST_F(BadInput, ReservedFlagBits) {
  auto b = hello_bytes();
  put_u32(b, 8, 0x80000000u);
  expect_fatal(b, ErrorCode::ReservedFlags, "flags");
}

TEST_F(BadInput, OversizeLengthRejectedBeforeAllocation) {
  auto b = hello_bytes();
  put_u32(b, 12, 0xFFFFFFF0u);  // a HELLO can never be 4 GiB
  expect_fatal(std::vector<uint8_t>(b.begin(), b.begin() + 24), ErrorCode::MessageTooLarge, "payload_length");
}

TEST_F(BadInput, FrameLargerThanServerLimit) {
  RawClient c(server_->tcp_url());
  c.hello();
  auto b = protocol::encode(protocol::Ping{1}, 3);
  b[6] = static_cast<uint8_t>(protocol::MessageType::Frame);
  put_u32(b, 12, 100u << 20);  // 100 MiB against --max-message 64M
  c.send_bytes(std::vector<uint8_t>(b.begin(), b.begin() + 24));
  auto r = c.receive(10.0);
  ASSERT_TRUE(r);
  auto* e = std::get_if<protocol::Error>(&r->message);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->code, ErrorCode::MessageTooLarge);
  EXPECT_TRUE(c.closed_by_server());
}

TEST_F(BadInput, FrameLargerThanOwnSessionsNeedIsRefusedBeforeAllocation) {
  // The server allows a peer at most twice its largest session's frame: a
  // client cannot make it allocate max_message_bytes by merely claiming it.
  for (bool with_session : {false, true}) {
    RawClient c(server_->tcp_url());
    c.hello();
    if (with_session) c.open(passthrough_session(64, 32));  // frames of ~24 KiB
    auto b = protocol::encode(protocol::Ping{1}, 3);
    b[6] = static_cast<uint8_t>(protocol::MessageType::Frame);
    put_u32(b, 12, 8u << 20);  // 8 MiB: within --max-message 64M, far beyond this peer's needs
    c.send_bytes(std::vector<uint8_t>(b.begin(), b.begin() + 24));
    auto r = c.receive(10.0);
    ASSERT_TRUE(r);
    auto* e = std::get_if<protocol::Error>(&r->message);
    ASSERT_NE(e, nullptr);
    EXPECT_EQ(e->code, ErrorCode::MessageTooLarge) << e->message;
    EXPECT_TRUE(c.closed_by_server());
  }
}

TEST_F(BadInput, UnknownMessageType) {
  auto b = hello_bytes();
  b[6] = 0xE7;
  b[7] = 0x03;  // type 999
  expect_fatal(b, ErrorCode::UnknownMessageType, "type");
}

TEST_F(BadInput, MessageBeforeHello) {
  expect_fatal(protocol::encode(protocol::Ping{5}, 1), ErrorCode::NotReady, "type");
}

TEST_F(BadInput, TruncatedMessageThenDisconnect) {
  for (int i = 0; i < 5; ++i) {
    RawClient c(server_->tcp_url());
    c.hello();
    auto f = make_frame(1, 0, 64, 32, passthrough_session(64, 32).channels, 1.0f);
    auto bytes = protocol::encode(f.frame, 9);
    bytes.resize(bytes.size() / 2);
    c.send_bytes(bytes);
    c.close();
  }
  // The server still answers a new client.
  RawClient probe(server_->tcp_url());
  probe.hello();
  probe.send(protocol::Ping{42}, 2);
  auto r = probe.receive();
  ASSERT_TRUE(r);
  ASSERT_NE(std::get_if<protocol::Pong>(&r->message), nullptr);
  EXPECT_EQ(std::get<protocol::Pong>(r->message).payload, 42u);
}

// Expects ERROR(code) naming `field_part` in reply to request_id, with the connection still usable.
void expect_request_error(RawClient& c, uint64_t request_id, ErrorCode code, const std::string& field_part) {
  auto r = c.receive(10.0);
  ASSERT_TRUE(r) << "no reply";
  auto* e = std::get_if<protocol::Error>(&r->message);
  ASSERT_NE(e, nullptr) << "expected ERROR, got " << protocol::to_string(r->header.type);
  EXPECT_EQ(r->header.request_id, request_id);
  EXPECT_EQ(e->code, code) << e->field << ": " << e->message;
  EXPECT_NE(e->field.find(field_part), std::string::npos) << "field '" << e->field << "'";
  EXPECT_FALSE(e->message.empty());
  c.send(protocol::Ping{77}, 5000 + request_id);
  auto pong = c.receive(10.0);
  ASSERT_TRUE(pong) << "connection unusable after a request error";
  EXPECT_NE(std::get_if<protocol::Pong>(&pong->message), nullptr);
}

TEST_F(BadInput, MalformedPayloadKeepsConnection) {
  RawClient c(server_->tcp_url());
  c.hello();
  auto b = protocol::encode(passthrough_session(64, 32), 4);
  // OPEN_SESSION payload: width(4) height(4) pipeline(2+11) output_format(1): set the format to 7.
  b[24 + 8 + 2 + 11] = 7;
  c.send_bytes(b);
  expect_request_error(c, 4, ErrorCode::Malformed, "output_format");
}

TEST_F(BadInput, UnknownPipelineNamed) {
  RawClient c(server_->tcp_url());
  c.hello();
  auto request = passthrough_session(64, 32);
  request.pipeline = "no-such-filter";
  c.send(request, 11);
  expect_request_error(c, 11, ErrorCode::UnknownPipeline, "pipeline");
}

TEST_F(BadInput, FrameForUnknownSession) {
  RawClient c(server_->tcp_url());
  c.hello();
  auto f = make_frame(123456789, 0, 64, 32, passthrough_session(64, 32).channels, 1.0f);
  c.send(f.frame, 21);
  expect_request_error(c, 21, ErrorCode::UnknownSession, "session_id");
}

TEST_F(BadInput, FrameForSomeoneElsesSession) {
  RawClient owner(server_->tcp_url());
  owner.hello();
  auto request = passthrough_session(64, 32);
  uint64_t sid = owner.open(request);
  RawClient intruder(server_->tcp_url());
  intruder.hello();
  auto f = make_frame(sid, 0, 64, 32, request.channels, 1.0f);
  intruder.send(f.frame, 22);
  expect_request_error(intruder, 22, ErrorCode::UnknownSession, "session_id");
  // The owner's session is untouched: its first frame is frame 0 and works.
  owner.send(f.frame, 23);
  auto r = owner.receive();
  ASSERT_TRUE(r);
  ASSERT_NE(std::get_if<protocol::Result>(&r->message), nullptr);
  EXPECT_EQ(r->header.request_id, 23u);
}

TEST_F(BadInput, PlaneOfWrongSize) {
  RawClient c(server_->tcp_url());
  c.hello();
  auto request = passthrough_session(64, 32);
  uint64_t sid = c.open(request);
  auto f = make_frame(sid, 0, 64, 31, request.channels, 1.0f);  // one row short
  c.send(f.frame, 31);
  expect_request_error(c, 31, ErrorCode::InvalidChannel, "byte_length");
}

TEST_F(BadInput, MissingRequiredChannelAtOpen) {
  RawClient c(server_->tcp_url());
  c.hello();
  auto request = passthrough_session(64, 32);
  request.pipeline = "accumulate";  // needs radiance, normal, depth and motion
  request.channels = {{protocol::ChannelId::Radiance, protocol::Format::F32},
                      {protocol::ChannelId::Normal, protocol::Format::F32},
                      {protocol::ChannelId::Depth, protocol::Format::F32}};
  c.send(request, 41);
  expect_request_error(c, 41, ErrorCode::MissingChannel, "channels");
}

TEST_F(BadInput, MissingDeclaredChannelInFrame) {
  RawClient c(server_->tcp_url());
  c.hello();
  auto request = passthrough_session(64, 32);
  uint64_t sid = c.open(request);
  auto f = make_frame(sid, 0, 64, 32, request.channels, 1.0f);
  f.frame.planes.clear();
  c.send(f.frame, 42);
  expect_request_error(c, 42, ErrorCode::MissingChannel, "planes");
}

TEST_F(BadInput, UndeclaredChannelInFrame) {
  RawClient c(server_->tcp_url());
  c.hello();
  auto request = passthrough_session(64, 32);
  uint64_t sid = c.open(request);
  auto f = make_frame(sid, 0, 64, 32, {{protocol::ChannelId::Radiance, protocol::Format::F32},
                                       {protocol::ChannelId::Albedo, protocol::Format::F32}},
                      1.0f);
  c.send(f.frame, 43);
  expect_request_error(c, 43, ErrorCode::InvalidChannel, "planes[1]");
}

TEST_F(BadInput, WrongPlaneFormat) {
  RawClient c(server_->tcp_url());
  c.hello();
  auto request = passthrough_session(64, 32);
  uint64_t sid = c.open(request);
  auto f = make_frame(sid, 0, 64, 32, {{protocol::ChannelId::Radiance, protocol::Format::F16}}, 1.0f);
  c.send(f.frame, 44);
  expect_request_error(c, 44, ErrorCode::InvalidChannel, "format");
}

TEST_F(BadInput, FrameIndexMustIncrease) {
  RawClient c(server_->tcp_url());
  c.hello();
  auto request = passthrough_session(64, 32);
  uint64_t sid = c.open(request);
  auto f5 = make_frame(sid, 5, 64, 32, request.channels, 1.0f);
  c.send(f5.frame, 51);
  auto r = c.receive();
  ASSERT_TRUE(r);
  ASSERT_NE(std::get_if<protocol::Result>(&r->message), nullptr);
  auto f3 = make_frame(sid, 3, 64, 32, request.channels, 1.0f);
  c.send(f3.frame, 52);
  expect_request_error(c, 52, ErrorCode::OutOfOrder, "frame_index");
}

TEST_F(BadInput, ServerOnlyMessageFromClient) {
  RawClient c(server_->tcp_url());
  c.hello();
  c.send(protocol::SessionClosed{1, 2}, 61);
  expect_request_error(c, 61, ErrorCode::UnknownMessageType, "type");
}

}  // namespace
}  // namespace dn::test
