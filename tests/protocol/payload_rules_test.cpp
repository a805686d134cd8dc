// Payload validation rules, each against the documented byte offsets
// (docs/protocol.md): a valid message is encoded, one byte range patched,
// and the error's code and field are checked.
#include <gtest/gtest.h>

#include <algorithm>

#include <bit>
#include <cmath>
#include <limits>

#include "support.hpp"

namespace dn::protocol::test {
namespace {

// Decodes header + payload of `bytes`, expecting failure.
DecodeError expect_error(const std::vector<uint8_t>& bytes) {
  Decoded d;
  std::vector<uint8_t> storage;
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  EXPECT_TRUE(err) << "decoded although invalid";
  return err ? *err : DecodeError{ErrorCode::Internal, "<none>", "<none>"};
}
void expect_ok(const std::vector<uint8_t>& bytes) {
  Decoded d;
  std::vector<uint8_t> storage;
  auto err = decode_message(bytes, kMaxMessage, d, storage);
  EXPECT_FALSE(err) << err->field << ": " << err->message;
}

constexpr size_t P = kHeaderSize;  // payload offset inside an encoded message

// OPEN_SESSION with pipeline "svgf" (6 bytes), no parameters unless given.
OpenSession open_session(std::vector<ChannelDecl> channels, std::vector<Parameter> params = {}) {
  OpenSession o;
  o.width = 64;
  o.height = 32;
  o.pipeline = "svgf";
  o.parameters = std::move(params);
  o.channels = std::move(channels);
  return o;
}
// Offsets for the OPEN_SESSION above without parameters:
// 0 width, 4 height, 8 pipeline (2+4), 14 output_format, 15 reserved, 16 parameter count,
// 18 channel count, 20 channels (2 bytes each).
constexpr size_t kOsChannels = 20;

TEST(PayloadRules, OpenSessionZeroWidthAndHeight) {
  auto bytes = encode(open_session({}));
  expect_ok(bytes);
  put_u32(bytes, P + 0, 0);
  auto e = expect_error(bytes);
  EXPECT_EQ(e.code, ErrorCode::Malformed);
  EXPECT_EQ(e.field, "OPEN_SESSION.width");
  bytes = encode(open_session({}));
  put_u32(bytes, P + 4, 0);
  EXPECT_EQ(expect_error(bytes).field, "OPEN_SESSION.height");
}

TEST(PayloadRules, OpenSessionChannelFormatOutOfRange) {
  const std::vector<ChannelDecl> ch = {{ChannelId::Radiance, Format::F32},
                                       {ChannelId::Albedo, Format::F16},
                                       {ChannelId::Normal, Format::F16},
                                       {ChannelId::Depth, Format::F32}};
  for (int bad : {0, 3, 255}) {
    auto bytes = encode(open_session(ch));
    bytes[P + kOsChannels + 3 * 2 + 1] = static_cast<uint8_t>(bad);
    auto e = expect_error(bytes);
    EXPECT_EQ(e.code, ErrorCode::Malformed);
    EXPECT_EQ(e.field, "OPEN_SESSION.channels[3].format");
  }
}

TEST(PayloadRules, OpenSessionChannelIds) {
  const std::vector<ChannelDecl> ch = {{ChannelId::Radiance, Format::F32}, {ChannelId::Depth, Format::F32}};
  // Unknown id.
  for (int bad : {22, 31, 55, 63, 64, 255}) {  // 12-14: the lighting forms, 15-21: reflection features, 33-50: extra samples, 51-54: sample statistics (docs/protocol.md §7)
    auto bytes = encode(open_session(ch));
    bytes[P + kOsChannels + 2] = static_cast<uint8_t>(bad);
    auto e = expect_error(bytes);
    EXPECT_EQ(e.code, ErrorCode::Malformed);
    EXPECT_EQ(e.field, "OPEN_SESSION.channels[1].id") << bad;
  }
  // Output is not an input channel.
  auto bytes = encode(open_session(ch));
  bytes[P + kOsChannels + 2] = 32;
  EXPECT_EQ(expect_error(bytes).field, "OPEN_SESSION.channels[1].id");
  // Duplicate: the second one is named.
  bytes = encode(open_session(ch));
  bytes[P + kOsChannels + 2] = 0;
  auto e = expect_error(bytes);
  EXPECT_EQ(e.field, "OPEN_SESSION.channels[1].id");
  EXPECT_NE(e.message.find("radiance"), std::string::npos) << e.message;
}

// Which ids each minor defines (docs/protocol.md §7, §10): 1.5 adds the
// sample statistics 51-54 (§7.7) and nothing else; 55-63 stay undefined.
TEST(PayloadRules, ChannelIdsOfEachMinor) {
  auto ids = [](uint32_t lo, uint32_t hi) {
    uint64_t m = 0;
    for (uint32_t id = lo; id <= hi; ++id) m |= uint64_t{1} << id;
    return m;
  };
  EXPECT_EQ(channels_defined_in(2) & ~channels_defined_in(1), ids(12, 14));
  EXPECT_EQ(channels_defined_in(3) & ~channels_defined_in(2), ids(15, 21));
  EXPECT_EQ(channels_defined_in(4) & ~channels_defined_in(3), ids(33, 50));
  EXPECT_EQ(channels_defined_in(5) & ~channels_defined_in(4), ids(51, 54));
  EXPECT_EQ(channels_defined_in(kVersionMinor), channels_defined_in(255));  // this version defines every id it knows
  EXPECT_EQ(channels_defined_in(kVersionMinor) & ids(22, 31), 0u);
  EXPECT_EQ(channels_defined_in(kVersionMinor) & ids(55, 63), 0u);
  const struct {
    ChannelId id;
    const char* name;
    uint32_t components;
  } stats[] = {{ChannelId::StatCount, "stat_count", 1},
               {ChannelId::StatMean, "stat_mean", 3},
               {ChannelId::StatM2, "stat_m2", 3},
               {ChannelId::StatM3, "stat_m3", 3}};
  for (uint32_t k = 0; k < 4; ++k) {
    const ChannelInfo* c = find_channel(stats[k].id);
    ASSERT_NE(c, nullptr) << stats[k].name;
    EXPECT_EQ(static_cast<uint32_t>(c->id), 51 + k);
    EXPECT_EQ(c->name, stats[k].name);
    EXPECT_EQ(c->components, stats[k].components) << stats[k].name;
    EXPECT_EQ(c->since_minor, 5) << stats[k].name;
    EXPECT_EQ(find_channel(stats[k].name), c);
    EXPECT_FALSE(sample_field(stats[k].id)) << stats[k].name;  // not an extra-sample channel
  }
}

// The statistics decode in OPEN_SESSION in either format: F32 only is the
// server's rule (INVALID_CHANNEL, docs/protocol.md §7.7), not the decoder's.
TEST(PayloadRules, OpenSessionTakesTheStatisticIds) {
  const std::vector<ChannelDecl> ch = {{ChannelId::Radiance, Format::F16},
                                       {ChannelId::StatCount, Format::F32},
                                       {ChannelId::StatMean, Format::F32},
                                       {ChannelId::StatM2, Format::F32},
                                       {ChannelId::StatM3, Format::F16}};
  const auto bytes = encode(open_session(ch));
  Decoded d;
  std::vector<uint8_t> storage;
  const auto err = decode_message(bytes, kMaxMessage, d, storage);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  const auto& o = std::get<OpenSession>(d.message);
  ASSERT_EQ(o.channels.size(), ch.size());
  for (size_t i = 0; i < ch.size(); ++i) {
    EXPECT_EQ(o.channels[i].id, ch[i].id) << i;
    EXPECT_EQ(o.channels[i].format, ch[i].format) << i;
  }
  // Byte 20 + 2 i is channel i's id: 51 ... 54 on the wire.
  for (size_t i = 1; i < ch.size(); ++i) EXPECT_EQ(bytes[P + kOsChannels + 2 * i], 50 + i);
}

TEST(PayloadRules, OpenSessionReservedAndOutputFormat) {
  auto bytes = encode(open_session({}));
  bytes[P + 15] = 1;
  EXPECT_EQ(expect_error(bytes).field, "OPEN_SESSION.reserved");
  bytes = encode(open_session({}));
  bytes[P + 14] = 0;
  EXPECT_EQ(expect_error(bytes).field, "OPEN_SESSION.output_format");
}

TEST(PayloadRules, OpenSessionParameters) {
  // parameters[0] at 18: name (2+5 "alpha"), value f64 at 25; parameters[1] at 33.
  auto bytes = encode(open_session({}, {{"alpha", 0.5}, {"sigma", 4.0}}));
  expect_ok(bytes);
  const uint64_t nan = std::bit_cast<uint64_t>(std::numeric_limits<double>::quiet_NaN());
  const uint64_t inf = std::bit_cast<uint64_t>(-std::numeric_limits<double>::infinity());
  for (uint64_t bad : {nan, inf}) {
    auto b = bytes;
    put_u64(b, P + 25, bad);
    auto e = expect_error(b);
    EXPECT_EQ(e.code, ErrorCode::Malformed);
    EXPECT_EQ(e.field, "OPEN_SESSION.parameters[0].value");
  }
  // Same name twice.
  auto b = bytes;
  std::copy_n("alpha", 5, b.begin() + P + 35);
  EXPECT_EQ(expect_error(b).field, "OPEN_SESSION.parameters[1].name");
}

TEST(PayloadRules, FrameFields) {
  Frame f;
  f.info.session_id = 1;
  const uint8_t px[6] = {1, 2, 3, 4, 5, 6};
  f.planes = {{ChannelId::Radiance, Format::F16, px}, {ChannelId::Depth, Format::F32, std::span(px).first(4)}};
  const auto good = encode(f);
  expect_ok(good);
  const uint32_t nan = 0x7FC00000u, inf = 0x7F800000u;

  auto b = good;
  put_u32(b, P + 24 + 5 * 4, nan);  // view[5]
  auto e = expect_error(b);
  EXPECT_EQ(e.code, ErrorCode::Malformed);
  EXPECT_EQ(e.field, "FRAME.view[5]");

  b = good;
  put_u32(b, P + 88 + 15 * 4, inf);
  EXPECT_EQ(expect_error(b).field, "FRAME.projection[15]");
  b = good;
  put_u32(b, P + 152, nan);
  EXPECT_EQ(expect_error(b).field, "FRAME.prev_view[0]");
  b = good;
  put_u32(b, P + 216 + 4, nan);
  EXPECT_EQ(expect_error(b).field, "FRAME.prev_projection[1]");
  b = good;
  put_u32(b, P + 284, inf | 0x80000000u);
  EXPECT_EQ(expect_error(b).field, "FRAME.jitter[1]");
  b = good;
  put_u32(b, P + 288, nan);
  EXPECT_EQ(expect_error(b).field, "FRAME.prev_jitter[0]");

  b = good;
  put_u32(b, P + 16, 2);  // undefined frame flag
  e = expect_error(b);
  EXPECT_EQ(e.code, ErrorCode::ReservedFlags);
  EXPECT_EQ(e.field, "FRAME.flags");

  b = good;
  b[P + 20] = 3;
  e = expect_error(b);
  EXPECT_EQ(e.code, ErrorCode::Malformed);
  EXPECT_EQ(e.field, "FRAME.motion");

  for (size_t i = 21; i < 24; ++i) {
    b = good;
    b[P + i] = 0x80;
    EXPECT_EQ(expect_error(b).field, "FRAME.reserved");
  }
}

TEST(PayloadRules, FramePlanes) {
  Frame f;
  const uint8_t px[6] = {1, 2, 3, 4, 5, 6};
  f.planes = {{ChannelId::Radiance, Format::F16, px}, {ChannelId::Depth, Format::F32, std::span(px).first(4)}};
  const auto good = encode(f);
  // planes[0] at 298: id, format, reserved u16 at 300, byte_length at 302, bytes at 310 (6)
  // planes[1] at 316: id, format at 317, reserved at 318, byte_length at 320, bytes at 328 (4); end 332.
  ASSERT_EQ(good.size(), P + 332);

  auto b = good;
  b[P + 301] = 1;
  auto e = expect_error(b);
  EXPECT_EQ(e.code, ErrorCode::Malformed);
  EXPECT_EQ(e.field, "FRAME.planes[0].reserved");

  b = good;
  b[P + 316] = 0;  // radiance again
  EXPECT_EQ(expect_error(b).field, "FRAME.planes[1].id");

  b = good;
  b[P + 317] = 7;
  EXPECT_EQ(expect_error(b).field, "FRAME.planes[1].format");

  b = good;
  put_u64(b, P + 320, 5);  // one byte more than is left
  e = expect_error(b);
  EXPECT_EQ(e.field, "FRAME.planes[1].byte_length");
  EXPECT_NE(e.message.find("remain"), std::string::npos);

  b = good;
  put_u64(b, P + 320, ~uint64_t{0});
  EXPECT_EQ(expect_error(b).field, "FRAME.planes[1].byte_length");

  b = good;
  put_u64(b, P + 320, 3);  // one byte left over
  e = expect_error(b);
  EXPECT_EQ(e.field, "FRAME");
  EXPECT_EQ(e.message, "FRAME: 1 trailing bytes");

  // Output planes may travel in a FRAME as far as the codec is concerned.
  b = good;
  b[P + 316] = 32;
  expect_ok(b);
}

TEST(PayloadRules, TrailingBytesNamedWithCount) {
  auto b = encode(Frame{});
  b.insert(b.end(), 12, 0);
  put_u32(b, 12, 296 + 2 + 12);
  auto e = expect_error(b);
  EXPECT_EQ(e.code, ErrorCode::Malformed);
  EXPECT_EQ(e.field, "FRAME");
  EXPECT_EQ(e.message, "FRAME: 12 trailing bytes");
}

TEST(PayloadRules, NewerMinorVersionMayAppendFields) {
  // A HELLO with 3 appended bytes: trailing at this version's minor and
  // below, the next minor's fields at kVersionMinor + 1.
  const auto newer = static_cast<uint8_t>(kVersionMinor + 1);
  auto hello = encode(Hello{0, "x", ""});
  hello.insert(hello.end(), {9, 9, 9});
  put_u32(hello, 12, static_cast<uint32_t>(hello.size() - P));
  EXPECT_EQ(expect_error(hello).message, "HELLO: 3 trailing bytes");
  hello[5] = 0;  // minor 0
  EXPECT_EQ(expect_error(hello).message, "HELLO: 3 trailing bytes");
  hello[5] = newer;
  expect_ok(hello);
  // A newer minor may also set capability bits this version does not know;
  // they are dropped, so the decoded HELLO is a valid message of this version.
  put_u32(hello, P, 0x10);
  {
    Decoded d;
    std::vector<uint8_t> storage;
    ASSERT_FALSE(decode_message(hello, kMaxMessage, d, storage));
    EXPECT_EQ(std::get<Hello>(d.message).capabilities, 0u);
    EXPECT_EQ(std::get<Hello>(d.message).client_name, "x");
    EXPECT_NO_THROW(encode(d.message));
  }
  for (int minor = 0; minor <= kVersionMinor; ++minor) {
    hello[5] = static_cast<uint8_t>(minor);
    auto e = expect_error(hello);
    EXPECT_EQ(e.code, ErrorCode::ReservedFlags);
    EXPECT_EQ(e.field, "HELLO.capabilities");
  }
}

TEST(PayloadRules, SessionReadOnlyIsBool) {
  Session s;
  s.width = 1;
  s.height = 1;
  s.pipeline = "ab";
  s.watch_key = "";
  s.watch_url = "";
  s.pipeline_reason = "";
  auto b = encode(s);
  // 0 session_id, 8 width, 12 height, 16 pipeline (2+2), 20 output_format, 21 read_only, 22 device_bytes, 30 channels
  b[P + 21] = 1;
  Decoded d;
  std::vector<uint8_t> storage;
  ASSERT_FALSE(decode_message(b, kMaxMessage, d, storage));
  EXPECT_TRUE(std::get<Session>(d.message).read_only);
  b[P + 21] = 2;
  EXPECT_EQ(expect_error(b).field, "SESSION.read_only");
}

TEST(PayloadRules, ErrorCodeMustBeKnown) {
  auto b = encode(Error{ErrorCode::Timeout, "f", "m"});
  for (uint32_t bad : {0u, 20u, 0xFFFFFFFFu}) {
    put_u32(b, P, bad);
    auto e = expect_error(b);
    EXPECT_EQ(e.code, ErrorCode::Malformed);
    EXPECT_EQ(e.field, "ERROR.code");
  }
}

TEST(PayloadRules, StringLimitsAndEncoding) {
  // client_name: 64 bytes accepted, 65 refused.
  expect_ok(encode(Hello{0, std::string(64, 'n'), std::string(256, 't')}));
  auto b = encode(Hello{0, std::string(64, 'n'), ""});
  b.insert(b.begin() + P + 6 + 64, 'n');
  put_u16(b, P + 4, 65);
  put_u32(b, 12, static_cast<uint32_t>(b.size() - P));
  auto e = expect_error(b);
  EXPECT_EQ(e.code, ErrorCode::Malformed);
  EXPECT_EQ(e.field, "HELLO.client_name");

  // auth_token over 256.
  b = encode(Hello{0, "", std::string(256, 't')});
  b.push_back('t');
  put_u16(b, P + 6, 257);
  put_u32(b, 12, static_cast<uint32_t>(b.size() - P));
  EXPECT_EQ(expect_error(b).field, "HELLO.auth_token");

  // NUL and invalid UTF-8 are refused; valid multibyte text is kept.
  for (std::string bad : {std::string("a\0b", 3), std::string("\xC3"), std::string("\xC0\xAF"),
                          std::string("\xED\xA0\x80"), std::string("\xF4\x90\x80\x80"), std::string("\xFF")}) {
    Hello h{0, std::string(bad.size(), 'x'), ""};
    b = encode(h);
    std::copy(bad.begin(), bad.end(), b.begin() + P + 6);
    EXPECT_EQ(expect_error(b).field, "HELLO.client_name");
  }
  expect_ok(encode(Hello{0, "caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80", ""}));

  // A string cut short by the end of the payload.
  b = encode(Hello{0, "abcdef", ""});
  put_u16(b, P + 4, 9);
  e = expect_error(b);
  EXPECT_EQ(e.field, "HELLO.client_name");
  EXPECT_NE(e.message.find("truncated"), std::string::npos);
}

TEST(PayloadRules, ListCountsCheckedBeforeReserving) {
  // STATS with a count the remaining bytes cannot hold.
  auto b = encode(Stats{{{"a", 1.0}}});
  put_u16(b, P, 200);
  auto e = expect_error(b);
  EXPECT_EQ(e.code, ErrorCode::Malformed);
  EXPECT_EQ(e.field, "STATS.values");
  EXPECT_NE(e.message.find("remain"), std::string::npos);
  // Over the documented maximum.
  put_u16(b, P, 257);
  e = expect_error(b);
  EXPECT_EQ(e.field, "STATS.values");
  EXPECT_NE(e.message.find("limit"), std::string::npos);
  // Planes: count 65 > 64.
  b = encode(Result{});
  put_u16(b, P + 18, 65);
  EXPECT_EQ(expect_error(b).field, "RESULT.planes");
}

TEST(PayloadRules, FixedSizeMessagesTruncated) {
  auto b = encode(SessionClosed{1, 2});
  b.resize(b.size() - 3);
  put_u32(b, 12, 13);
  auto e = expect_error(b);
  EXPECT_EQ(e.field, "SESSION_CLOSED.frames_processed");
}

TEST(PayloadRules, PayloadLengthMustMatchGivenBytes) {
  Header h;
  h.type = MessageType::Ping;
  h.payload_length = 8;
  Message m;
  const uint8_t p[4] = {};
  auto err = decode_payload(h, p, m);
  ASSERT_TRUE(err);
  EXPECT_EQ(err->field, "header.payload_length");
}

TEST(Encode, RefusesWhatDecodeWouldRefuse) {
  EXPECT_THROW(encode(Hello{0, std::string(65, 'x'), ""}), std::invalid_argument);
  EXPECT_THROW(encode(Hello{1, "", ""}), std::invalid_argument);
  EXPECT_THROW(encode(open_session({}, {{"a", std::nan("")}})), std::invalid_argument);
  EXPECT_THROW(encode(open_session({{ChannelId::Depth, Format::F16}, {ChannelId::Depth, Format::F32}})),
               std::invalid_argument);
  EXPECT_THROW(encode(open_session({{ChannelId::Output, Format::F16}})), std::invalid_argument);
  EXPECT_THROW(encode(OpenSession{}), std::invalid_argument);  // width 0
  EXPECT_THROW(encode(Error{static_cast<ErrorCode>(0), "", ""}), std::invalid_argument);
  Frame f;
  f.info.view[3] = std::numeric_limits<float>::infinity();
  EXPECT_THROW(encode(f), std::invalid_argument);
  // Unrepresentable sizes.
  EXPECT_THROW(encode(Error{ErrorCode::Internal, std::string(70000, 'x'), ""}), std::length_error);
  // Header flags.
  EXPECT_THROW(encode(Ping{}, 0, kFlagNoOutput), std::invalid_argument);
  EXPECT_THROW(encode(Frame{}, 0, 2), std::invalid_argument);
  // The output buffer is left as it was.
  std::vector<uint8_t> out = {1, 2, 3};
  EXPECT_THROW(encode(Hello{0, std::string(65, 'x'), ""}, 0, 0, out), std::invalid_argument);
  EXPECT_EQ(out, (std::vector<uint8_t>{1, 2, 3}));
}

}  // namespace
}  // namespace dn::protocol::test
