// Golden bytes: written by hand from docs/protocol.md (not produced by
// encode()), so they pin the documented layout in both directions.
#include <gtest/gtest.h>

#include "support.hpp"

namespace dn::protocol::test {
namespace {

// HELLO, request_id 7, client_name "cli", auth_token "tk"; header version 1.minor.
std::vector<uint8_t> golden_hello(int minor) {
  return Bytes{}
      .raw({0x44, 0x4E, 0x53, 0x56})  // magic "DNSV"
      .raw({0x01, minor})             // version 1.0 ... 1.9
      .raw({0x01, 0x00})              // type 1 = HELLO
      .raw({0x00, 0x00, 0x00, 0x00})  // flags
      .raw({0x0D, 0x00, 0x00, 0x00})  // payload_length 13
      .raw({0x07, 0, 0, 0, 0, 0, 0, 0})  // request_id 7
      // payload
      .raw({0x00, 0x00, 0x00, 0x00})       // capabilities
      .raw({0x03, 0x00}).text("cli")       // client_name
      .raw({0x02, 0x00}).text("tk")        // auth_token
      .v;
}

// FRAME with NO_OUTPUT, request_id 0x1122334455667788, one 2-pixel F16 depth plane.
std::vector<uint8_t> golden_frame(int minor) {
  return Bytes{}
      .raw({0x44, 0x4E, 0x53, 0x56, 0x01, minor})  // magic, version 1.minor
      .raw({0x06, 0x00})                          // type 6 = FRAME
      .raw({0x01, 0x00, 0x00, 0x00})              // flags NO_OUTPUT
      .raw({0x3A, 0x01, 0x00, 0x00})              // payload_length 314
      .raw({0x88, 0x77, 0x66, 0x55, 0x44, 0x33, 0x22, 0x11})
      // payload offset 0: session_id 0x0102030405060708
      .raw({0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01})
      .raw({0x2A, 0, 0, 0, 0, 0, 0, 0})  // 8: frame_index 42
      .raw({0x01, 0x00, 0x00, 0x00})     // 16: flags RESET
      .raw({0x02})                       // 20: motion UV_TO_PREVIOUS
      .raw({0x00, 0x00, 0x00})           // 21: reserved
      // 24: view = identity (column-major)
      .raw({0x00, 0x00, 0x80, 0x3F}).zeros(16)
      .raw({0x00, 0x00, 0x80, 0x3F}).zeros(16)
      .raw({0x00, 0x00, 0x80, 0x3F}).zeros(16)
      .raw({0x00, 0x00, 0x80, 0x3F})
      // 88: projection: [0] = 0.5, [14] = -1
      .raw({0x00, 0x00, 0x00, 0x3F}).zeros(13 * 4)
      .raw({0x00, 0x00, 0x80, 0xBF}).zeros(4)
      // 152: prev_view: [12] = 3 (translation x)
      .zeros(12 * 4).raw({0x00, 0x00, 0x40, 0x40}).zeros(3 * 4)
      // 216: prev_projection: zero
      .zeros(64)
      // 280: jitter (0.25, -0.5); 288: prev_jitter (0, 0)
      .raw({0x00, 0x00, 0x80, 0x3E, 0x00, 0x00, 0x00, 0xBF})
      .zeros(8)
      // 296: plane count 1
      .raw({0x01, 0x00})
      // 298: id 7 (depth), format 1 (F16), reserved, byte_length 4
      .raw({0x07, 0x01, 0x00, 0x00})
      .raw({0x04, 0, 0, 0, 0, 0, 0, 0})
      // 310: half 1.0, half 2.0
      .raw({0x00, 0x3C, 0x00, 0x40})
      .v;
}

// OPEN_SESSION 1920x1080 "svgf", F16 output, alpha = 0.2, radiance F32 + depth F16.
std::vector<uint8_t> golden_open_session(int minor) {
  return Bytes{}
      .raw({0x44, 0x4E, 0x53, 0x56, 0x01, minor, 0x04, 0x00})  // magic, 1.minor, type 4
      .raw({0, 0, 0, 0})                                      // flags
      .raw({0x27, 0, 0, 0})                                   // payload_length 39
      .raw({0x01, 0, 0, 0, 0, 0, 0, 0})                       // request_id 1
      .raw({0x80, 0x07, 0, 0})                                // width 1920
      .raw({0x38, 0x04, 0, 0})                                // height 1080
      .raw({0x04, 0x00}).text("svgf")                         // pipeline
      .raw({0x01})                                            // output_format F16
      .raw({0x00})                                            // reserved
      .raw({0x01, 0x00})                                      // 1 parameter
      .raw({0x05, 0x00}).text("alpha")
      .raw({0x9A, 0x99, 0x99, 0x99, 0x99, 0x99, 0xC9, 0x3F})  // 0.2
      .raw({0x02, 0x00})                                      // 2 channels
      .raw({0x00, 0x02})                                      // radiance F32
      .raw({0x07, 0x01})                                      // depth F16
      .v;
}

TEST(Golden, HelloDecodes) {
  const auto bytes = golden_hello(0);  // a 1.0 client's HELLO still decodes
  ASSERT_EQ(bytes.size(), 24u + 13u);
  Header h;
  ASSERT_FALSE(decode_header(bytes, kMaxMessage, h));
  EXPECT_EQ(h.magic, 0x56534E44u);
  EXPECT_EQ(h.version_major, 1);
  EXPECT_EQ(h.version_minor, 0);
  EXPECT_EQ(h.type, MessageType::Hello);
  EXPECT_EQ(h.flags, 0u);
  EXPECT_EQ(h.payload_length, 13u);
  EXPECT_EQ(h.request_id, 7u);
  Message m;
  ASSERT_FALSE(decode_payload(h, std::span(bytes).subspan(24), m));
  const auto& hello = std::get<Hello>(m);
  EXPECT_EQ(hello.capabilities, 0u);
  EXPECT_EQ(hello.client_name, "cli");
  EXPECT_EQ(hello.auth_token, "tk");
}

TEST(Golden, HelloEncodes) {
  Hello hello{0, "cli", "tk"};
  EXPECT_EQ(encode(hello, 7, 0), golden_hello(kVersionMinor));  // the sender's own version
}

TEST(Golden, HelloOfEitherMinorDecodesTheSame) {
  for (int minor : {0, 1, 2, 3, 4, 5, 6}) {
    Decoded d;
    std::vector<uint8_t> storage;
    const auto bytes = golden_hello(minor);
    auto err = decode_message(bytes, kMaxMessage, d, storage);
    ASSERT_FALSE(err) << minor << ": " << err->field << ": " << err->message;
    EXPECT_EQ(d.header.version_minor, minor);
    EXPECT_EQ(diff(Hello{0, "cli", "tk"}, d.message), "");
  }
}

TEST(Golden, FrameDecodes) {
  const auto bytes = golden_frame(0);
  ASSERT_EQ(bytes.size(), 24u + 314u);
  Header h;
  ASSERT_FALSE(decode_header(bytes, kMaxMessage, h));
  EXPECT_EQ(h.type, MessageType::Frame);
  EXPECT_EQ(h.flags, kFlagNoOutput);
  EXPECT_EQ(h.payload_length, 314u);
  EXPECT_EQ(h.request_id, 0x1122334455667788u);
  const std::span<const uint8_t> payload = std::span(bytes).subspan(24);
  Message m;
  auto err = decode_payload(h, payload, m);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  const auto& f = std::get<Frame>(m);
  EXPECT_EQ(f.info.session_id, 0x0102030405060708u);
  EXPECT_EQ(f.info.frame_index, 42u);
  EXPECT_EQ(f.info.flags, kFrameReset);
  EXPECT_EQ(f.info.motion, MotionConvention::UvToPrevious);
  const Mat4 identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  EXPECT_EQ(f.info.view, identity);
  Mat4 projection{};
  projection[0] = 0.5f;
  projection[14] = -1.0f;
  EXPECT_EQ(f.info.projection, projection);
  Mat4 prev_view{};
  prev_view[12] = 3.0f;
  EXPECT_EQ(f.info.prev_view, prev_view);
  EXPECT_EQ(f.info.prev_projection, Mat4{});
  EXPECT_EQ(f.info.jitter, (std::array<float, 2>{0.25f, -0.5f}));
  EXPECT_EQ(f.info.prev_jitter, (std::array<float, 2>{0.0f, 0.0f}));
  ASSERT_EQ(f.planes.size(), 1u);
  EXPECT_EQ(f.planes[0].id, ChannelId::Depth);
  EXPECT_EQ(f.planes[0].format, Format::F16);
  ASSERT_EQ(f.planes[0].bytes.size(), 4u);
  // Zero copy: the plane views the payload at offset 310.
  EXPECT_EQ(f.planes[0].bytes.data(), payload.data() + 310);
  EXPECT_EQ(half_to_float(uint16_t(f.planes[0].bytes[0] | f.planes[0].bytes[1] << 8)), 1.0f);
  EXPECT_EQ(half_to_float(uint16_t(f.planes[0].bytes[2] | f.planes[0].bytes[3] << 8)), 2.0f);
}

TEST(Golden, FrameEncodes) {
  Frame f;
  f.info.session_id = 0x0102030405060708u;
  f.info.frame_index = 42;
  f.info.flags = kFrameReset;
  f.info.motion = MotionConvention::UvToPrevious;
  f.info.view = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  f.info.projection[0] = 0.5f;
  f.info.projection[14] = -1.0f;
  f.info.prev_view[12] = 3.0f;
  f.info.jitter = {0.25f, -0.5f};
  const uint8_t depth[4] = {0x00, 0x3C, 0x00, 0x40};
  f.planes.push_back({ChannelId::Depth, Format::F16, depth});
  EXPECT_EQ(encode(f, 0x1122334455667788u, kFlagNoOutput), golden_frame(kVersionMinor));
}

TEST(Golden, OpenSessionBothWays) {
  const auto bytes = golden_open_session(kVersionMinor);
  OpenSession o;
  o.width = 1920;
  o.height = 1080;
  o.pipeline = "svgf";
  o.output_format = Format::F16;
  o.parameters = {{"alpha", 0.2}};
  o.channels = {{ChannelId::Radiance, Format::F32}, {ChannelId::Depth, Format::F16}};
  EXPECT_EQ(encode(o, 1, 0), bytes);

  Decoded d;
  std::vector<uint8_t> storage;
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  EXPECT_EQ(d.header.request_id, 1u);
  EXPECT_EQ(diff(o, d.message), "");
  // The same payload from a 1.0 client.
  const auto old = golden_open_session(0);
  ASSERT_FALSE(decode_message(old, kMaxMessage, d, storage));
  EXPECT_EQ(diff(o, d.message), "");
}

// SESSION, request_id 3, session 0x0102030405060708, 640x360 "svgf", F16
// output, not read-only, 4096 device bytes, one channel (radiance F32), and
// from 1.6 the watch key (§5.5), from 1.8 the watch URL, from 1.10 the
// reason for an "auto" choice.
const char* const kKey = "0123456789abcdef0123456789abcdef";
const char* const kUrl = "tcp://lb:7101";
const char* const kReason = "full G-buffer";
std::vector<uint8_t> golden_session(int minor) {
  Bytes b;
  b.raw({0x44, 0x4E, 0x53, 0x56, 0x01, minor})  // magic, version 1.minor
      .raw({0x05, 0x00})                        // type 5 = SESSION
      .raw({0x00, 0x00, 0x00, 0x00})            // flags
      // payload_length 36, 70 with the key, 85 with the URL, 100 with the reason
      .raw({minor >= 10 ? 0x64 : minor >= 8 ? 0x55 : minor >= 6 ? 0x46 : 0x24, 0x00, 0x00, 0x00})
      .raw({0x03, 0, 0, 0, 0, 0, 0, 0})         // request_id 3
      // payload
      .raw({0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01})  // 0: session_id
      .raw({0x80, 0x02, 0x00, 0x00})                          // 8: width 640
      .raw({0x68, 0x01, 0x00, 0x00})                          // 12: height 360
      .raw({0x04, 0x00}).text("svgf")                         // 16: pipeline
      .raw({0x01})                                            // +0: output_format F16
      .raw({0x00})                                            // +1: read_only 0
      .raw({0x00, 0x10, 0, 0, 0, 0, 0, 0})                    // +2: device_bytes 4096
      .raw({0x01, 0x00, 0x00, 0x02});                         // +10: 1 channel, radiance F32
  if (minor >= 6) b.raw({0x20, 0x00}).text(kKey);             // 1.6: watch_key, 32 bytes
  if (minor >= 8) b.raw({0x0D, 0x00}).text(kUrl);             // 1.8: watch_url, 13 bytes
  if (minor >= 10) b.raw({0x0D, 0x00}).text(kReason);         // 1.10: pipeline_reason, 13 bytes
  return b.v;
}

// ATTACH, request_id 9, session 0x0102030405060708, from 1.6 with the key (§5.8).
std::vector<uint8_t> golden_attach(int minor) {
  Bytes b;
  b.raw({0x44, 0x4E, 0x53, 0x56, 0x01, minor})  // magic, version 1.minor
      .raw({0x08, 0x00})                        // type 8 = ATTACH
      .raw({0x00, 0x00, 0x00, 0x00})            // flags
      .raw({minor >= 6 ? 0x2A : 0x08, 0x00, 0x00, 0x00})  // payload_length 8, 42 with the key
      .raw({0x09, 0, 0, 0, 0, 0, 0, 0})         // request_id 9
      .raw({0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01});  // session_id
  if (minor >= 6) b.raw({0x20, 0x00}).text(kKey);             // 1.6: watch_key
  return b.v;
}

Session golden_session_message(std::optional<std::string> key, std::optional<std::string> url = std::nullopt,
                               std::optional<std::string> reason = std::nullopt) {
  Session s{0x0102030405060708u, 640, 360, "svgf", Format::F16, 4096, false, {{ChannelId::Radiance, Format::F32}}};
  s.watch_key = std::move(key);
  s.watch_url = std::move(url);
  s.pipeline_reason = std::move(reason);
  return s;
}

TEST(Golden, SessionWithTheWatchKeyBothWays) {
  const Session s = golden_session_message(kKey);
  // To a 1.6 or 1.7 client: the 1.7 payload under this sender's own minor.
  std::vector<uint8_t> expected = golden_session(7);
  expected[5] = kVersionMinor;
  EXPECT_EQ(encode(s, 3, 0), expected);
  Decoded d;
  std::vector<uint8_t> storage;
  auto bytes = golden_session(6);
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  EXPECT_EQ(diff(s, d.message), "");
}

TEST(Golden, SessionWithTheWatchUrlBothWays) {
  const Session s = golden_session_message(kKey, kUrl);
  // To a 1.8 or 1.9 client: the 1.9 payload under this sender's own minor.
  std::vector<uint8_t> expected = golden_session(9);
  expected[5] = kVersionMinor;
  EXPECT_EQ(encode(s, 3, 0), expected);
  Decoded d;
  std::vector<uint8_t> storage;
  auto bytes = golden_session(8);
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  EXPECT_EQ(diff(s, d.message), "");
  // A URL needs the key before it on the wire.
  EXPECT_THROW(encode(golden_session_message(std::nullopt, kUrl), 3, 0), std::invalid_argument);
}

TEST(Golden, SessionWithThePipelineReasonBothWays) {
  const Session s = golden_session_message(kKey, kUrl, kReason);
  EXPECT_EQ(encode(s, 3, 0), golden_session(kVersionMinor));
  Decoded d;
  std::vector<uint8_t> storage;
  auto bytes = golden_session(10);
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  EXPECT_EQ(diff(s, d.message), "");
  // A reason needs the URL before it on the wire.
  EXPECT_THROW(encode(golden_session_message(kKey, std::nullopt, kReason), 3, 0), std::invalid_argument);
}

TEST(Golden, PipelineReasonIsOneLineOfPrintableAscii) {
  auto bytes = golden_session(10);
  bytes[bytes.size() - 3] = '\n';  // "full G-buff\ner"
  Decoded d;
  std::vector<uint8_t> storage;
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  ASSERT_TRUE(err) << "a reason with a line break decoded";
  EXPECT_EQ(err->code, ErrorCode::Malformed);
  EXPECT_EQ(err->field, "SESSION.pipeline_reason");
}

TEST(Golden, WatchUrlIsPrintableAscii) {
  auto bytes = golden_session(8);
  bytes[bytes.size() - 5] = ' ';  // "tcp://lb 7101"
  Decoded d;
  std::vector<uint8_t> storage;
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  ASSERT_TRUE(err) << "a watch URL with a space decoded";
  EXPECT_EQ(err->code, ErrorCode::Malformed);
  EXPECT_EQ(err->field, "SESSION.watch_url");
}

TEST(Golden, SessionFromAnOlderServerHasNoKey) {
  for (int minor : {0, 5}) {
    Decoded d;
    std::vector<uint8_t> storage;
    auto bytes = golden_session(minor);
    auto err = decode_message(bytes, kMaxMessage, d, storage);
    ASSERT_FALSE(err) << minor << ": " << err->field << ": " << err->message;
    EXPECT_EQ(diff(golden_session_message(std::nullopt), d.message), "") << minor;
  }
  // A 1.9 server answering a 1.5 client: its own minor in the header, the 1.5 payload.
  std::vector<uint8_t> expected = golden_session(5);
  expected[5] = kVersionMinor;
  EXPECT_EQ(encode(golden_session_message(std::nullopt), 3, 0), expected);
}

TEST(Golden, AttachWithTheWatchKeyBothWays) {
  const Attach a{0x0102030405060708u, kKey};
  EXPECT_EQ(encode(a, 9, 0), golden_attach(kVersionMinor));
  Decoded d;
  std::vector<uint8_t> storage;
  auto bytes = golden_attach(6);
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  EXPECT_EQ(diff(a, d.message), "");
  auto old = golden_attach(5);
  ASSERT_FALSE(decode_message(old, kMaxMessage, d, storage));
  EXPECT_EQ(diff(Attach{0x0102030405060708u, std::nullopt}, d.message), "");
}

TEST(Golden, WatchKeyMustBeEmptyOrThirtyTwoLowercaseHexDigits) {
  for (const char* bad : {"0123456789ABCDEF0123456789abcdef", "0123456789abcdef0123456789abcdeg", "0123"}) {
    SCOPED_TRACE(bad);
    for (auto make : {golden_attach, golden_session}) {
      std::vector<uint8_t> bytes = make(6);
      const size_t at = bytes.size() - 34;  // the key's u16 length, then its 32 bytes
      bytes.resize(at);
      const std::string key = bad;
      Bytes tail;
      tail.raw({static_cast<int>(key.size()), 0x00}).text(key);
      bytes.insert(bytes.end(), tail.v.begin(), tail.v.end());
      const size_t length = bytes.size() - 24;
      bytes[12] = static_cast<uint8_t>(length);  // payload_length, little-endian; below 256 here
      bytes[13] = 0;
      Decoded d;
      std::vector<uint8_t> storage;
      auto err = decode_message(bytes, kMaxMessage, d, storage);
      ASSERT_TRUE(err);
      EXPECT_EQ(err->code, ErrorCode::Malformed);
      EXPECT_NE(err->field.find(".watch_key"), std::string::npos) << err->field;
      EXPECT_NE(err->message.find("lowercase hex"), std::string::npos) << err->message;
    }
  }
  // Empty is well-formed: an ATTACH without a key is the server's to refuse.
  Decoded d;
  std::vector<uint8_t> storage;
  const auto empty = encode(Attach{1, ""}, 1, 0);
  ASSERT_FALSE(decode_message(empty, kMaxMessage, d, storage));
  EXPECT_EQ(std::get<Attach>(d.message).watch_key, std::optional<std::string>(""));
}

// RESULT, request_id 4, session 0x0102030405060708, frame 2, no timings, no
// planes (a NO_OUTPUT frame), and from 1.9 the sample counts: counted, min 3,
// median 8 (§5.7).
std::vector<uint8_t> golden_result(int minor) {
  Bytes b;
  b.raw({0x44, 0x4E, 0x53, 0x56, 0x01, minor})  // magic, version 1.minor
      .raw({0x07, 0x00})                        // type 7 = RESULT
      .raw({0x00, 0x00, 0x00, 0x00})            // flags
      .raw({minor >= 9 ? 0x1D : 0x14, 0x00, 0x00, 0x00})  // payload_length 20, 29 with the counts
      .raw({0x04, 0, 0, 0, 0, 0, 0, 0})         // request_id 4
      // payload
      .raw({0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01})  // 0: session_id
      .raw({0x02, 0, 0, 0, 0, 0, 0, 0})                       // 8: frame_index 2
      .raw({0x00, 0x00})                                      // 16: no timings
      .raw({0x00, 0x00});                                     // 18: no planes
  if (minor >= 9) b.raw({0x01}).raw({0x03, 0x00, 0x00, 0x00}).raw({0x08, 0x00, 0x00, 0x00});  // 1.9: samples
  return b.v;
}

Result golden_result_message(std::optional<SampleCounts> samples) {
  Result r;
  r.session_id = 0x0102030405060708u;
  r.frame_index = 2;
  r.samples = samples;
  return r;
}

TEST(Golden, ResultWithTheSampleCountsBothWays) {
  const Result r = golden_result_message(SampleCounts{true, 3, 8});
  std::vector<uint8_t> expected = golden_result(9);
  expected[5] = kVersionMinor;  // 1.10 appended nothing to RESULT
  EXPECT_EQ(encode(r, 4, 0), expected);
  Decoded d;
  std::vector<uint8_t> storage;
  auto bytes = golden_result(9);
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  EXPECT_EQ(diff(r, d.message), "");
}

TEST(Golden, ResultWithoutCountsIsTheOlderPayload) {
  // To a client before 1.9: the 1.8 payload under this sender's own minor.
  std::vector<uint8_t> expected = golden_result(8);
  expected[5] = kVersionMinor;
  EXPECT_EQ(encode(golden_result_message(std::nullopt), 4, 0), expected);
  Decoded d;
  std::vector<uint8_t> storage;
  auto bytes = golden_result(8);
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  EXPECT_EQ(diff(golden_result_message(std::nullopt), d.message), "");
}

TEST(Golden, ResultFromAPipelineWithoutACount) {
  // To a 1.9 client the field is there, not counted: 9 bytes, all 0.
  std::vector<uint8_t> expected = golden_result(9);
  expected[5] = kVersionMinor;
  for (size_t i = expected.size() - 9; i < expected.size(); ++i) expected[i] = 0;
  EXPECT_EQ(encode(golden_result_message(SampleCounts{}), 4, 0), expected);
  Decoded d;
  std::vector<uint8_t> storage;
  auto err = decode_message(expected, kMaxMessage, d, storage);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  EXPECT_EQ(diff(golden_result_message(SampleCounts{}), d.message), "");
}

TEST(Golden, ResultSampleCountsThatCannotBeAreMalformed) {
  struct Case {
    size_t from_end;  // the byte changed, counted from the end of the message
    uint8_t value;
    const char* field;
  };
  // counted 2; min 9 above median 8; not counted with a min of 3.
  for (const Case& c : {Case{9, 0x02, "RESULT.samples.counted"}, Case{8, 0x09, "RESULT.samples.min"},
                        Case{9, 0x00, "RESULT.samples.min"}}) {
    auto bytes = golden_result(9);
    bytes[bytes.size() - c.from_end] = c.value;
    Decoded d;
    std::vector<uint8_t> storage;
    auto err = decode_message(bytes, kMaxMessage, d, storage);
    ASSERT_TRUE(err) << c.field << " decoded";
    EXPECT_EQ(err->code, ErrorCode::Malformed);
    EXPECT_EQ(err->field, c.field);
  }
}

}  // namespace
}  // namespace dn::protocol::test
