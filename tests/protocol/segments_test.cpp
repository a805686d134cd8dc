// encode_segments(): the gathered pieces are byte for byte what encode()
// writes, plane data is referenced rather than copied, and invalid messages
// are rejected the same way.
#include <gtest/gtest.h>

#include "support.hpp"

namespace dn::protocol::test {
namespace {

std::vector<uint8_t> concatenate(const std::vector<std::span<const uint8_t>>& segments) {
  std::vector<uint8_t> out;
  for (auto s : segments) out.insert(out.end(), s.begin(), s.end());
  return out;
}

TEST(EncodeSegments, SameBytesAsEncodeForEveryType) {
  std::mt19937 rng(1234);
  std::vector<uint8_t> scratch;
  std::vector<std::span<const uint8_t>> segments;
  for (int round = 0; round < 200; ++round) {
    for (MessageType type : kAllTypes) {
      OwnedMessage m = random_message(type, rng, 300);
      const uint32_t flags = random_flags(type, rng);
      const uint64_t id = rng();
      encode_segments(m.message, id, flags, scratch, segments);
      ASSERT_EQ(concatenate(segments), encode(m.message, id, flags)) << to_string(type);
    }
  }
}

TEST(EncodeSegments, PlaneBytesAreReferencedNotCopied) {
  std::vector<uint8_t> a(1000, 1), b(4000, 2);
  Frame f;
  f.info.session_id = 9;
  f.planes = {{ChannelId::Radiance, Format::F32, a}, {ChannelId::Albedo, Format::F16, b}};
  std::vector<uint8_t> scratch;
  std::vector<std::span<const uint8_t>> segments;
  encode_segments(f, 1, 0, scratch, segments);
  int referenced = 0;
  for (auto s : segments) referenced += (s.data() == a.data() && s.size() == a.size()) + (s.data() == b.data() && s.size() == b.size());
  EXPECT_EQ(referenced, 2);
  EXPECT_LT(scratch.size(), 500u);  // header and fields only
}

TEST(EncodeSegments, RejectsWhatEncodeRejects) {
  std::vector<uint8_t> a(12, 0);
  Frame f;
  f.planes = {{ChannelId::Radiance, Format::F32, a}, {ChannelId::Radiance, Format::F32, a}};  // duplicate
  std::vector<uint8_t> scratch;
  std::vector<std::span<const uint8_t>> segments;
  EXPECT_THROW(encode_segments(f, 1, 0, scratch, segments), std::invalid_argument);
  EXPECT_THROW(encode(f, 1, 0), std::invalid_argument);
}

TEST(SegmentCursor, PartialSendsReassembleTheMessage) {
  std::mt19937 rng(99);
  OwnedMessage m = random_message(MessageType::Frame, rng, 5000);
  std::vector<uint8_t> scratch;
  std::vector<std::span<const uint8_t>> segments;
  encode_segments(m.message, 5, 0, scratch, segments);
  const std::vector<uint8_t> expected = encode(m.message, 5, 0);
  for (int trial = 0; trial < 50; ++trial) {
    // A "socket" that takes a random number of bytes from the first few pieces each time.
    SegmentCursor cursor;
    std::vector<uint8_t> sent;
    while (!cursor.done(segments)) {
      size_t budget = rng() % 700 + 1;
      size_t taken = 0;
      for (size_t i = cursor.segment; i < segments.size() && budget > 0; ++i) {
        auto piece = cursor.remaining(segments, i);
        const size_t n = std::min(budget, piece.size());
        sent.insert(sent.end(), piece.begin(), piece.begin() + static_cast<long>(n));
        budget -= n;
        taken += n;
        if (n < piece.size()) break;
      }
      cursor.advance(segments, taken);
    }
    ASSERT_EQ(sent, expected);
  }
}

}  // namespace
}  // namespace dn::protocol::test
