// The fixed header's rules, one by one, in the documented order.
#include <gtest/gtest.h>

#include "support.hpp"

namespace dn::protocol::test {
namespace {

struct RawHeader {
  uint32_t magic = 0x56534E44;
  uint8_t major = 1, minor = 0;
  uint16_t type = 9;  // PING
  uint32_t flags = 0;
  uint32_t length = 8;
  uint64_t request_id = 0;

  std::vector<uint8_t> bytes() const {
    std::vector<uint8_t> b(24);
    put_u32(b, 0, magic);
    b[4] = major;
    b[5] = minor;
    put_u16(b, 6, type);
    put_u32(b, 8, flags);
    put_u32(b, 12, length);
    put_u64(b, 16, request_id);
    return b;
  }
};

std::optional<DecodeError> check(const RawHeader& raw, uint64_t max_message = kMaxMessage) {
  Header h;
  return decode_header(raw.bytes(), max_message, h);
}

TEST(Header, ValidPingIsAccepted) {
  RawHeader raw;
  raw.request_id = 0xDEADBEEFCAFEF00Du;
  Header h;
  ASSERT_FALSE(decode_header(raw.bytes(), kMaxMessage, h));
  EXPECT_EQ(h.type, MessageType::Ping);
  EXPECT_EQ(h.payload_length, 8u);
  EXPECT_EQ(h.request_id, 0xDEADBEEFCAFEF00Du);
}

TEST(Header, MagicBytesSpellDNSV) {
  const auto b = RawHeader{}.bytes();
  EXPECT_EQ(std::string(b.begin(), b.begin() + 4), "DNSV");
}

TEST(Header, WrongMagic) {
  RawHeader raw;
  raw.magic = 0x56534E45;
  auto err = check(raw);
  ASSERT_TRUE(err);
  EXPECT_EQ(err->code, ErrorCode::BadMagic);
  EXPECT_EQ(err->field, "header.magic");
}

TEST(Header, MagicCheckedBeforeEverythingElse) {
  RawHeader raw;
  raw.magic = 0x20544547;  // "GET " — an HTTP client
  raw.major = 9;
  raw.type = 999;
  raw.flags = 0xFF;
  raw.length = 0xFFFFFFFF;
  auto err = check(raw);
  ASSERT_TRUE(err);
  EXPECT_EQ(err->code, ErrorCode::BadMagic);
}

TEST(Header, MajorVersion2) {
  RawHeader raw;
  raw.major = 2;
  auto err = check(raw);
  ASSERT_TRUE(err);
  EXPECT_EQ(err->code, ErrorCode::UnsupportedVersion);
  EXPECT_EQ(err->field, "header.version_major");
}

TEST(Header, AnyMinorVersionIsAccepted) {
  for (int minor : {0, 1, 7, 255}) {
    RawHeader raw;
    raw.minor = static_cast<uint8_t>(minor);
    Header h;
    ASSERT_FALSE(decode_header(raw.bytes(), kMaxMessage, h)) << minor;
    EXPECT_EQ(h.version_minor, minor);
  }
}

TEST(Header, UnknownType) {
  for (uint16_t type : {0, 15, 999, 0xFFFF}) {
    RawHeader raw;
    raw.type = type;
    auto err = check(raw);
    ASSERT_TRUE(err) << type;
    EXPECT_EQ(err->code, ErrorCode::UnknownMessageType);
    EXPECT_EQ(err->field, "header.type");
    EXPECT_NE(err->message.find(std::to_string(type)), std::string::npos);
  }
}

TEST(Header, ReservedFlagBits) {
  for (uint32_t bit = 1; bit < 32; ++bit) {
    RawHeader raw;
    raw.type = 6;  // FRAME
    raw.length = 300;
    raw.flags = 1u << bit;
    auto err = check(raw);
    ASSERT_TRUE(err) << bit;
    EXPECT_EQ(err->code, ErrorCode::ReservedFlags);
    EXPECT_EQ(err->field, "header.flags");
  }
}

TEST(Header, NoOutputOnlyOnFrame) {
  for (MessageType type : kAllTypes) {
    RawHeader raw;
    raw.type = static_cast<uint16_t>(type);
    raw.length = 0;
    raw.flags = kFlagNoOutput;
    auto err = check(raw);
    if (type == MessageType::Frame) {
      EXPECT_FALSE(err);
    } else {
      ASSERT_TRUE(err) << to_string(type);
      EXPECT_EQ(err->code, ErrorCode::ReservedFlags);
      EXPECT_EQ(err->field, "header.flags");
    }
  }
}

TEST(Header, ShareInputOnlyOnOpenSession) {
  for (MessageType type : kAllTypes) {
    RawHeader raw;
    raw.type = static_cast<uint16_t>(type);
    raw.length = 0;
    raw.flags = kFlagShareInput;
    auto err = check(raw);
    if (type == MessageType::OpenSession) {
      EXPECT_FALSE(err);
    } else {
      ASSERT_TRUE(err) << to_string(type);
      EXPECT_EQ(err->code, ErrorCode::ReservedFlags);
      EXPECT_NE(err->message.find("SHARE_INPUT"), std::string::npos) << err->message;
    }
  }
}

TEST(Header, OversizeHelloNamesValueAndLimit) {
  RawHeader raw;
  raw.type = 1;  // HELLO
  raw.length = 70000;
  auto err = check(raw);
  ASSERT_TRUE(err);
  EXPECT_EQ(err->code, ErrorCode::MessageTooLarge);
  EXPECT_EQ(err->field, "header.payload_length");
  EXPECT_EQ(err->message, "payload_length 70000 exceeds the 4096-byte limit for HELLO");
  raw.length = 4096;
  EXPECT_FALSE(check(raw));
}

TEST(Header, FrameBoundedByMaxMessageBytes) {
  RawHeader raw;
  raw.type = 6;
  raw.length = 1000 - 24;
  EXPECT_FALSE(check(raw, 1000));
  raw.length = 1000 - 23;
  auto err = check(raw, 1000);
  ASSERT_TRUE(err);
  EXPECT_EQ(err->code, ErrorCode::MessageTooLarge);
  EXPECT_EQ(err->message, "payload_length 977 exceeds the 976-byte limit for FRAME");
}

TEST(Header, ShortInputIsMalformed) {
  const auto b = RawHeader{}.bytes();
  for (size_t n = 0; n < 24; ++n) {
    Header h;
    auto err = decode_header(std::span(b).first(n), kMaxMessage, h);
    ASSERT_TRUE(err);
    EXPECT_EQ(err->code, ErrorCode::Malformed);
    EXPECT_EQ(err->field, "header");
  }
}

TEST(Header, FailedDecodeLeavesOutputUntouched) {
  Header h;
  h.request_id = 77;
  RawHeader raw;
  raw.major = 3;
  ASSERT_TRUE(decode_header(raw.bytes(), kMaxMessage, h));
  EXPECT_EQ(h.request_id, 77u);
}

TEST(Header, MaxPayloadBytesTable) {
  const uint64_t big = uint64_t{1} << 32;
  EXPECT_EQ(max_payload_bytes(MessageType::Hello, big), 4096u);
  EXPECT_EQ(max_payload_bytes(MessageType::Welcome, big), 65536u);
  EXPECT_EQ(max_payload_bytes(MessageType::Error, big), 8192u);
  EXPECT_EQ(max_payload_bytes(MessageType::OpenSession, big), 65536u);
  EXPECT_EQ(max_payload_bytes(MessageType::Session, big), 65536u);
  EXPECT_EQ(max_payload_bytes(MessageType::Frame, big), big - 24);
  EXPECT_EQ(max_payload_bytes(MessageType::Result, big), big - 24);
  EXPECT_EQ(max_payload_bytes(MessageType::Attach, big), 42u);  // 1.6: u64 + a 32-byte watch_key string
  EXPECT_EQ(max_payload_bytes(MessageType::Ping, big), 8u);
  EXPECT_EQ(max_payload_bytes(MessageType::Pong, big), 8u);
  EXPECT_EQ(max_payload_bytes(MessageType::CloseSession, big), 8u);
  EXPECT_EQ(max_payload_bytes(MessageType::SessionClosed, big), 16u);
  EXPECT_EQ(max_payload_bytes(MessageType::StatsRequest, big), 0u);
  EXPECT_EQ(max_payload_bytes(MessageType::Stats, big), 65536u);
  EXPECT_EQ(max_payload_bytes(static_cast<MessageType>(999), big), 0u);
  // Everything is capped at max_message_bytes - 24.
  EXPECT_EQ(max_payload_bytes(MessageType::Welcome, 1024), 1000u);
  EXPECT_EQ(max_payload_bytes(MessageType::Ping, 30), 6u);
  EXPECT_EQ(max_payload_bytes(MessageType::Frame, 10), 0u);
}

TEST(Names, TypesAndCodes) {
  EXPECT_STREQ(to_string(MessageType::OpenSession), "OPEN_SESSION");
  EXPECT_STREQ(to_string(MessageType::SessionClosed), "SESSION_CLOSED");
  EXPECT_STREQ(to_string(MessageType::StatsRequest), "STATS_REQUEST");
  EXPECT_STREQ(to_string(ErrorCode::BadMagic), "BAD_MAGIC");
  EXPECT_STREQ(to_string(ErrorCode::Internal), "INTERNAL");
  for (uint32_t c = 1; c <= 19; ++c) EXPECT_STRNE(to_string(static_cast<ErrorCode>(c)), "UNKNOWN_ERROR_CODE") << c;
  EXPECT_STREQ(to_string(static_cast<ErrorCode>(0)), "UNKNOWN_ERROR_CODE");
  EXPECT_STREQ(to_string(static_cast<MessageType>(0)), "UNKNOWN_MESSAGE_TYPE");
  EXPECT_EQ(type_of(Message{Stats{}}), MessageType::Stats);
  EXPECT_EQ(type_of(Message{Hello{}}), MessageType::Hello);
  EXPECT_EQ(type_of(Message{Result{}}), MessageType::Result);
}

}  // namespace
}  // namespace dn::protocol::test
