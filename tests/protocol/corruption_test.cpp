// Damaged input: flipped bytes, every truncation, appended bytes. Decoding
// never crashes and either succeeds or names a field and a reason.
#include <gtest/gtest.h>

#include "support.hpp"

namespace dn::protocol::test {
namespace {

void expect_named(const DecodeError& e, const std::string& context) {
  EXPECT_FALSE(e.field.empty()) << context;
  EXPECT_FALSE(e.message.empty()) << context;
}

TEST(Corruption, FlippedBytes) {
  std::mt19937 rng(99);
  int accepted = 0, rejected = 0;
  for (MessageType type : kAllTypes) {
    for (int n = 0; n < 20; ++n) {
      OwnedMessage m = random_message(type, rng, 24);
      const std::vector<uint8_t> original = encode(m.message, rng(), random_flags(type, rng));
      for (int k = 0; k < 40; ++k) {
        std::vector<uint8_t> bytes = original;
        const int flips = std::uniform_int_distribution<int>(1, 4)(rng);
        for (int f = 0; f < flips; ++f) {
          const size_t at = std::uniform_int_distribution<size_t>(0, bytes.size() - 1)(rng);
          bytes[at] ^= static_cast<uint8_t>(std::uniform_int_distribution<int>(1, 255)(rng));
        }
        Decoded d;
        std::vector<uint8_t> storage;
        auto err = decode_message(bytes, kMaxMessage, d, storage);
        if (err) {
          ++rejected;
          expect_named(*err, std::string(to_string(type)));
          continue;
        }
        ++accepted;
        // Anything accepted at the current minor version re-encodes to exactly
        // the bytes that were read (the encoding is canonical).
        if (d.header.version_minor == kVersionMinor && d.header.payload_length == bytes.size() - kHeaderSize) {
          EXPECT_EQ(encode(d.message, d.header.request_id, d.header.flags), bytes) << to_string(type);
        }
      }
    }
  }
  EXPECT_GT(rejected, 0);
  EXPECT_GT(accepted, 0);
}

TEST(Corruption, EveryTruncationOfThePayloadIsMalformed) {
  std::mt19937 rng(7);
  for (MessageType type : kAllTypes) {
    for (int n = 0; n < 6; ++n) {
      // Keep messages small: the work grows with the square of the size.
      OwnedMessage m;
      do {
        m = random_message(type, rng, 16);
      } while (encode(m.message).size() > 1500);
      const std::vector<uint8_t> bytes = encode(m.message);
      Header h;
      ASSERT_FALSE(decode_header(bytes, kMaxMessage, h));
      const std::vector<uint8_t> payload(bytes.begin() + kHeaderSize, bytes.end());
      // Every field is fixed-size or length-prefixed, so every strict prefix is cut somewhere.
      for (size_t len = 0; len < payload.size(); ++len) {
        Header cut = h;
        cut.payload_length = static_cast<uint32_t>(len);
        Message out;
        auto err = decode_payload(cut, std::span(payload).first(len), out);
        ASSERT_TRUE(err) << to_string(type) << " accepted a " << len << "-byte prefix of " << payload.size();
        EXPECT_EQ(err->code, ErrorCode::Malformed);
        EXPECT_EQ(err->field.rfind(std::string(to_string(type)) + ".", 0), 0u) << err->field;
        EXPECT_NE(err->message.find("remain"), std::string::npos) << err->message;
      }
    }
  }
}

TEST(Corruption, TruncatedStreamNeverDecodes) {
  // The raw byte stream cut anywhere: the header or the payload length disagrees.
  std::mt19937 rng(8);
  for (MessageType type : kAllTypes) {
    OwnedMessage m = random_message(type, rng, 16);
    const std::vector<uint8_t> bytes = encode(m.message);
    for (size_t len = 0; len < bytes.size(); ++len) {
      Decoded d;
      std::vector<uint8_t> storage;
      auto err = decode_message(std::span(bytes).first(len), kMaxMessage, d, storage);
      ASSERT_TRUE(err) << to_string(type) << " length " << len;
      EXPECT_EQ(err->code, ErrorCode::Malformed);
      EXPECT_EQ(err->field, len < kHeaderSize ? "header" : "header.payload_length");
    }
  }
}

TEST(Corruption, AppendedBytesAreTrailing) {
  std::mt19937 rng(11);
  for (MessageType type : kAllTypes) {
    for (int n = 0; n < 10; ++n) {
      OwnedMessage m = random_message(type, rng, 16);
      std::vector<uint8_t> bytes = encode(m.message);
      const size_t extra = std::uniform_int_distribution<size_t>(1, 16)(rng);
      for (size_t i = 0; i < extra; ++i) bytes.push_back(static_cast<uint8_t>(rng()));
      put_u32(bytes, 12, static_cast<uint32_t>(bytes.size() - kHeaderSize));

      Decoded d;
      std::vector<uint8_t> storage;
      auto err = decode_message(bytes, kMaxMessage, d, storage);
      ASSERT_TRUE(err);
      if (err->code == ErrorCode::MessageTooLarge) {
        // Fixed-size control messages are already refused by their header.
        EXPECT_EQ(err->field, "header.payload_length");
        EXPECT_LT(max_payload_bytes(type, kMaxMessage), bytes.size() - kHeaderSize);
        continue;
      }
      EXPECT_EQ(err->code, ErrorCode::Malformed);
      EXPECT_EQ(err->field, to_string(type));
      EXPECT_EQ(err->message, std::string(to_string(type)) + ": " + std::to_string(extra) + " trailing bytes");
    }
  }
}

}  // namespace
}  // namespace dn::protocol::test
