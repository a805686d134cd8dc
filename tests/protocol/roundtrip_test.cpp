// decode(encode(m)) == m, field by field, for random contents of every type.
#include <gtest/gtest.h>

#include "support.hpp"

namespace dn::protocol::test {
namespace {

class RoundTrip : public ::testing::TestWithParam<MessageType> {};

TEST_P(RoundTrip, RandomContents) {
  const MessageType type = GetParam();
  std::mt19937 rng(1234 + static_cast<unsigned>(type));
  const int iterations = 300;
  for (int it = 0; it < iterations; ++it) {
    OwnedMessage m = random_message(type, rng);
    const uint64_t request_id = (static_cast<uint64_t>(rng()) << 32) | rng();
    const uint32_t flags = random_flags(type, rng);
    const std::vector<uint8_t> bytes = encode(m.message, request_id, flags);
    ASSERT_GE(bytes.size(), kHeaderSize);

    Decoded d;
    std::vector<uint8_t> storage;
    auto err = decode_message(bytes, kMaxMessage, d, storage);
    ASSERT_FALSE(err) << "iteration " << it << ": " << err->field << ": " << err->message;
    EXPECT_EQ(d.header.type, type);
    EXPECT_EQ(d.header.version_major, 1);
    EXPECT_EQ(d.header.version_minor, kVersionMinor);  // the sender's own minor
    EXPECT_EQ(d.header.flags, flags);
    EXPECT_EQ(d.header.request_id, request_id);
    EXPECT_EQ(d.header.payload_length, bytes.size() - kHeaderSize);
    ASSERT_EQ(type_of(d.message), type);
    ASSERT_EQ(diff(m.message, d.message), "") << "iteration " << it;

    // The encoding is canonical: re-encoding the decoded message gives the same bytes.
    ASSERT_EQ(encode(d.message, request_id, flags), bytes) << "iteration " << it;
  }
}

INSTANTIATE_TEST_SUITE_P(AllTypes, RoundTrip, ::testing::ValuesIn(kAllTypes),
                         [](const auto& info) { return std::string(to_string(info.param)); });

TEST(RoundTrip, EncodeAppendsToExistingBuffer) {
  std::vector<uint8_t> out = {0xAA, 0xBB};
  encode(Ping{5}, 9, 0, out);
  ASSERT_EQ(out.size(), 2u + 24u + 8u);
  EXPECT_EQ(out[0], 0xAA);
  EXPECT_EQ(out[1], 0xBB);
  Header h;
  ASSERT_FALSE(decode_header(std::span(out).subspan(2), kMaxMessage, h));
  EXPECT_EQ(h.type, MessageType::Ping);
  EXPECT_EQ(h.request_id, 9u);
}

TEST(RoundTrip, LargeFrameIsReservedOnceAndPlanesCopiedVerbatim) {
  // 2 planes of 1 MiB: the encoder computes the exact size before writing.
  std::vector<uint8_t> a(1 << 20), b(1 << 20);
  for (size_t i = 0; i < a.size(); ++i) {
    a[i] = uint8_t(i * 7);
    b[i] = uint8_t(i * 13 + 1);
  }
  Frame f;
  f.info.session_id = 3;
  f.planes = {{ChannelId::Radiance, Format::F32, a}, {ChannelId::Normal, Format::F16, b}};
  std::vector<uint8_t> out;
  encode(f, 0, 0, out);
  const size_t expected = 24 + 296 + 2 + 2 * (12 + (1 << 20));
  EXPECT_EQ(out.size(), expected);
  EXPECT_EQ(out.capacity(), expected);  // reserved exactly once, no growth
  Decoded d;
  std::vector<uint8_t> storage;
  ASSERT_FALSE(decode_message(out, 8 << 20, d, storage));
  EXPECT_EQ(diff(f, d.message), "");
}

}  // namespace
}  // namespace dn::protocol::test
