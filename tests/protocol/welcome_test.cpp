// WELCOME across minor versions (docs/protocol.md §5.2, §10): the 1.0
// payload, the 1.1 parameter tables appended to it, and the rules on them.
// Golden bytes are written by hand from the spec, not produced by encode().
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <limits>

#include "support.hpp"

namespace dn::protocol::test {
namespace {

constexpr size_t P = kHeaderSize;

// Header of a WELCOME with request_id 5.
Bytes welcome_header(int minor, int payload_length) {
  return Bytes{}
      .raw({0x44, 0x4E, 0x53, 0x56})        // magic
      .raw({0x01, minor})                   // version 1.minor
      .raw({0x02, 0x00})                    // type 2 = WELCOME
      .raw({0x00, 0x00, 0x00, 0x00})        // flags
      .raw({payload_length, 0x00, 0x00, 0x00})
      .raw({0x05, 0, 0, 0, 0, 0, 0, 0});    // request_id 5
}

// The 1.0 fields (84 bytes): "dn" on "cpu", limits, pipelines "acc" and "pt".
Bytes& welcome_1_0_fields(Bytes& b) {
  return b.raw({0x02, 0x00}).text("dn")                  // 0 server_version
      .raw({0x03, 0x00}).text("cpu")                     // 4 device_name
      .raw({0x00, 0x00, 0x10, 0x00, 0, 0, 0, 0})         // 9 max_message_bytes 1 MiB
      .raw({0x00, 0x00, 0x00, 0x40, 0, 0, 0, 0})         // 17 max_session_bytes 1 GiB
      .raw({0x08, 0, 0, 0})                              // 25 max_sessions 8
      .raw({0x00, 0x10, 0, 0})                           // 29 max_width 4096
      .raw({0x00, 0x08, 0, 0})                           // 33 max_height 2048
      .raw({0x03, 0, 0, 0})                              // 37 max_frames_in_flight 3
      .raw({0x02, 0x00})                                 // 41 two pipelines
      .raw({0x03, 0x00}).text("acc")                     // 43 pipelines[0].name
      .raw({0x89, 0, 0, 0, 0, 0, 0, 0})                  //    required: radiance, albedo, depth
      .raw({0x00, 0x02, 0, 0, 0, 0, 0, 0})               //    optional: emission
      .raw({0x02, 0x00}).text("pt")                      // 64 pipelines[1].name
      .raw({0x01, 0, 0, 0, 0, 0, 0, 0})                  //    required: radiance
      .raw({0, 0, 0, 0, 0, 0, 0, 0});                    //    optional: none; ends at 84
}

// The 1.1 extension (41 bytes): "acc" takes integer k = 4 in [1, 8], "pt" nothing.
Bytes& pipeline_parameters(Bytes& b) {
  return b.raw({0x02, 0x00})                             // 84 pipeline_parameters: 2 lists
      .raw({0x01, 0x00})                                 // 86 [0]: one parameter
      .raw({0x01, 0x00}).text("k")                       // 88 [0][0].name
      .raw({0, 0, 0, 0, 0, 0, 0x10, 0x40})               // 91 default_value 4.0
      .raw({0, 0, 0, 0, 0, 0, 0xF0, 0x3F})               // 99 min_value 1.0
      .raw({0, 0, 0, 0, 0, 0, 0x20, 0x40})               // 107 max_value 8.0
      .raw({0x01})                                       // 115 integer
      .raw({0x05, 0x00}).text("Taps.")                   // 116 description
      .raw({0x00, 0x00});                                // 123 [1]: no parameters; ends at 125
}

std::vector<uint8_t> golden_welcome_1_0(int header_minor) {
  Bytes b = welcome_header(header_minor, 84);
  return welcome_1_0_fields(b).v;
}

// The 1.1 payload (1.2 appended nothing to WELCOME) under a header of
// minor `header_minor` (the sender's own: 1 to 5).
std::vector<uint8_t> golden_welcome_1_1(int header_minor = 1) {
  Bytes b = welcome_header(header_minor, 125);
  welcome_1_0_fields(b);
  return pipeline_parameters(b).v;
}

Welcome expected_welcome(bool with_parameters) {
  Welcome w;
  w.server_version = "dn";
  w.device_name = "cpu";
  w.limits = {1u << 20, 1u << 30, 8, 4096, 2048, 3};
  w.pipelines = {{"acc", 0x89, 0x200, {}}, {"pt", 0x1, 0x0, {}}};
  if (with_parameters) {
    w.has_parameters = true;
    w.pipelines[0].parameters = {{"k", 4.0, 1.0, 8.0, true, "Taps."}};
  }
  return w;
}

DecodeError expect_error(const std::vector<uint8_t>& bytes) {
  Decoded d;
  std::vector<uint8_t> storage;
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  EXPECT_TRUE(err) << "decoded although invalid";
  return err ? *err : DecodeError{ErrorCode::Internal, "<none>", "<none>"};
}

TEST(Welcome, GoldenOneOneBothWays) {
  const auto bytes = golden_welcome_1_1();
  ASSERT_EQ(bytes.size(), P + 125);
  EXPECT_EQ(encode(expected_welcome(true), 5, 0), golden_welcome_1_1(kVersionMinor));  // this sender's own header
  Decoded d;
  std::vector<uint8_t> storage;
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  EXPECT_EQ(diff(expected_welcome(true), d.message), "");
  EXPECT_TRUE(std::get<Welcome>(d.message).has_parameters);
}

TEST(Welcome, OneZeroServerStillDecodesWithoutParameters) {
  Decoded d;
  std::vector<uint8_t> storage;
  const auto bytes = golden_welcome_1_0(0);
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  const auto& w = std::get<Welcome>(d.message);
  EXPECT_FALSE(w.has_parameters);
  EXPECT_EQ(diff(expected_welcome(false), d.message), "");
}

TEST(Welcome, OneZeroClientGetsTheOneZeroPayloadUnderANewerHeader) {
  // A 1.9 server answering a 1.0 HELLO: its own minor in the header, only the 1.0 fields.
  EXPECT_EQ(encode(expected_welcome(false), 5, 0), golden_welcome_1_0(kVersionMinor));
  // A receiver that sent a HELLO of minor >= 1 requires the tables at minor 1.
  const auto e = expect_error(golden_welcome_1_0(1));
  EXPECT_EQ(e.code, ErrorCode::Malformed);
  EXPECT_EQ(e.field, "WELCOME.pipeline_parameters");
  EXPECT_NE(e.message.find("truncated"), std::string::npos) << e.message;
}

TEST(Welcome, OneZeroReceiverSkipsTheTables) {
  // What a 1.0 client sees from a 1.1 server that sent the tables anyway is
  // trailing bytes of a newer minor; at minor 0 they are refused.
  auto bytes = golden_welcome_1_1();
  bytes[5] = 0;
  auto e = expect_error(bytes);
  EXPECT_EQ(e.field, "WELCOME");
  EXPECT_EQ(e.message, "WELCOME: 41 trailing bytes");
}

TEST(Welcome, NewerMinorMayAppendAfterTheTables) {
  auto bytes = golden_welcome_1_1();
  bytes.insert(bytes.end(), {7, 7, 7});
  put_u32(bytes, 12, 128);
  EXPECT_EQ(expect_error(bytes).message, "WELCOME: 3 trailing bytes");
  bytes[5] = static_cast<uint8_t>(kVersionMinor + 1);
  Decoded d;
  std::vector<uint8_t> storage;
  ASSERT_FALSE(decode_message(bytes, kMaxMessage, d, storage));
  EXPECT_EQ(diff(expected_welcome(true), d.message), "");
}

TEST(Welcome, TableCountMustMatchPipelines) {
  auto bytes = golden_welcome_1_1();
  put_u16(bytes, P + 84, 1);
  auto e = expect_error(bytes);
  EXPECT_EQ(e.code, ErrorCode::Malformed);
  EXPECT_EQ(e.field, "WELCOME.pipeline_parameters");
  EXPECT_NE(e.message.find("differs from the 2 pipelines"), std::string::npos) << e.message;
  put_u16(bytes, P + 84, 65);
  EXPECT_EQ(expect_error(bytes).field, "WELCOME.pipeline_parameters");
}

TEST(Welcome, ParameterListCountCheckedBeforeReserving) {
  auto bytes = golden_welcome_1_1();
  put_u16(bytes, P + 86, 2);  // two entries of >= 29 bytes do not fit in what remains
  auto e = expect_error(bytes);
  EXPECT_EQ(e.field, "WELCOME.pipeline_parameters[0]");
  EXPECT_NE(e.message.find("remain"), std::string::npos) << e.message;
  put_u16(bytes, P + 86, 65);
  e = expect_error(bytes);
  EXPECT_EQ(e.field, "WELCOME.pipeline_parameters[0]");
  EXPECT_NE(e.message.find("limit of 64"), std::string::npos) << e.message;
}

TEST(Welcome, ParameterValuesFiniteAndOrdered) {
  const uint64_t nan = std::bit_cast<uint64_t>(std::numeric_limits<double>::quiet_NaN());
  const uint64_t inf = std::bit_cast<uint64_t>(std::numeric_limits<double>::infinity());
  const std::pair<size_t, const char*> fields[] = {
      {91, "default_value"}, {99, "min_value"}, {107, "max_value"}};
  for (const auto& [at, name] : fields) {
    for (uint64_t bad : {nan, inf}) {
      auto bytes = golden_welcome_1_1();
      put_u64(bytes, P + at, bad);
      auto e = expect_error(bytes);
      EXPECT_EQ(e.code, ErrorCode::Malformed);
      EXPECT_EQ(e.field, std::string("WELCOME.pipeline_parameters[0][0].") + name);
    }
  }
  auto bytes = golden_welcome_1_1();
  put_u64(bytes, P + 107, std::bit_cast<uint64_t>(0.5));  // max 0.5 < min 1
  EXPECT_EQ(expect_error(bytes).field, "WELCOME.pipeline_parameters[0][0].max_value");
  bytes = golden_welcome_1_1();
  put_u64(bytes, P + 91, std::bit_cast<uint64_t>(9.0));  // default above max
  EXPECT_EQ(expect_error(bytes).field, "WELCOME.pipeline_parameters[0][0].default_value");
  bytes = golden_welcome_1_1();
  put_u64(bytes, P + 91, std::bit_cast<uint64_t>(0.0));  // default below min
  EXPECT_EQ(expect_error(bytes).field, "WELCOME.pipeline_parameters[0][0].default_value");
  bytes = golden_welcome_1_1();
  put_u64(bytes, P + 91, std::bit_cast<uint64_t>(8.0));  // the bounds are inclusive
  Decoded d;
  std::vector<uint8_t> storage;
  EXPECT_FALSE(decode_message(bytes, kMaxMessage, d, storage));
}

TEST(Welcome, IntegerIsBool) {
  auto bytes = golden_welcome_1_1();
  bytes[P + 115] = 0;
  Decoded d;
  std::vector<uint8_t> storage;
  ASSERT_FALSE(decode_message(bytes, kMaxMessage, d, storage));
  EXPECT_FALSE(std::get<Welcome>(d.message).pipelines[0].parameters[0].integer);
  bytes[P + 115] = 2;
  auto e = expect_error(bytes);
  EXPECT_EQ(e.code, ErrorCode::Malformed);
  EXPECT_EQ(e.field, "WELCOME.pipeline_parameters[0][0].integer");
}

TEST(Welcome, NamesUniquePerPipelineAndDescriptionLimit) {
  Welcome w = expected_welcome(true);
  w.pipelines[0].parameters.push_back({"k", 1.0, 0.0, 2.0, false, ""});
  EXPECT_THROW(encode(w), std::invalid_argument);
  // The same name in two pipelines is fine.
  w = expected_welcome(true);
  w.pipelines[1].parameters = {{"k", 0.0, 0.0, 0.0, false, ""}};
  EXPECT_NO_THROW(encode(w));

  // Second name patched to equal the first: named as the second.
  w = expected_welcome(true);
  w.pipelines[0].parameters.push_back({"j", 1.0, 0.0, 2.0, false, ""});
  auto bytes = encode(w);
  // [0][1] starts after [0][0] (88 + 35 = 123): its name's byte at 125.
  ASSERT_EQ(bytes[P + 125], 'j');
  bytes[P + 125] = 'k';
  auto e = expect_error(bytes);
  EXPECT_EQ(e.field, "WELCOME.pipeline_parameters[0][1].name");
  EXPECT_NE(e.message.find("second time"), std::string::npos) << e.message;

  // Description: 512 bytes accepted, 513 refused; name: 64 / 65.
  w = expected_welcome(true);
  w.pipelines[0].parameters[0].description = std::string(512, 'd');
  EXPECT_NO_THROW(encode(w));
  w.pipelines[0].parameters[0].description = std::string(513, 'd');
  EXPECT_THROW(encode(w), std::invalid_argument);
  w = expected_welcome(true);
  w.pipelines[0].parameters[0].name = std::string(65, 'n');
  EXPECT_THROW(encode(w), std::invalid_argument);
}

TEST(Welcome, EncoderRefusesTablesThatWouldNotBeSent) {
  Welcome w = expected_welcome(true);
  w.has_parameters = false;  // parameters present but not announced
  EXPECT_THROW(encode(w), std::invalid_argument);
}

TEST(Welcome, EncoderKeepsThePayloadLimit) {
  // 64 pipelines x 3 parameters x ~600 bytes exceeds 65536: refused by the
  // encoder, since a receiver refuses such a header before reading it.
  Welcome w;
  w.has_parameters = true;
  for (int i = 0; i < 64; ++i) {
    PipelineInfo p{"p" + std::to_string(i), 0, 0, {}};
    for (int j = 0; j < 3; ++j) p.parameters.push_back({"q" + std::to_string(j), 0, 0, 0, false, std::string(512, 'x')});
    w.pipelines.push_back(std::move(p));
  }
  EXPECT_THROW(encode(w), std::invalid_argument);
  w.pipelines.resize(30);  // 30 x 3 x 548 + fixed part fits
  const auto bytes = encode(w);
  EXPECT_LE(bytes.size() - P, 65536u);
}

TEST(Welcome, EveryStrictPrefixOfTheOneOnePayloadIsRefused) {
  const auto bytes = golden_welcome_1_1();
  Header h;
  ASSERT_FALSE(decode_header(bytes, kMaxMessage, h));
  const std::vector<uint8_t> payload(bytes.begin() + P, bytes.end());
  for (size_t len = 0; len < payload.size(); ++len) {
    Header cut = h;
    cut.payload_length = static_cast<uint32_t>(len);
    Message out;
    auto err = decode_payload(cut, std::span(payload).first(len), out);
    ASSERT_TRUE(err) << len;
    EXPECT_NE(err->message.find("remain"), std::string::npos) << len << ": " << err->message;
  }
}

}  // namespace
}  // namespace dn::protocol::test
