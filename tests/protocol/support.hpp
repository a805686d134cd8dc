// Test helpers for the protocol suite: random valid messages, a field-by-field
// comparison, and byte-building helpers for hand-written wire data.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "dn/protocol/codec.hpp"

namespace dn::protocol::test {

// A message plus the storage its plane views point into.
struct OwnedMessage {
  Message message;
  std::vector<std::shared_ptr<std::vector<uint8_t>>> storage;
};

// Random contents that respect every documented rule (limits, finite floats,
// unique channels, ...). max_plane_bytes bounds each plane's size.
OwnedMessage random_message(MessageType type, std::mt19937& rng, size_t max_plane_bytes = 64);
// Random header flags valid for the type (NO_OUTPUT only on FRAME).
uint32_t random_flags(MessageType type, std::mt19937& rng);

inline constexpr MessageType kAllTypes[] = {
    MessageType::Hello,        MessageType::Welcome,       MessageType::Error,        MessageType::OpenSession,
    MessageType::Session,      MessageType::Frame,         MessageType::Result,       MessageType::Attach,
    MessageType::Ping,         MessageType::Pong,          MessageType::CloseSession, MessageType::SessionClosed,
    MessageType::StatsRequest, MessageType::Stats,
};

// "" when equal; otherwise a description of the first difference.
// Floating-point values are compared bit for bit; planes by content.
std::string diff(const Message& expected, const Message& actual);

// Header + payload of one complete encoded message.
struct Decoded {
  Header header;
  Message message;
};
// Runs decode_header then decode_payload on one message's bytes (the
// payload is copied so plane views may point into `storage`).
std::optional<DecodeError> decode_message(std::span<const uint8_t> bytes, uint64_t max_message_bytes, Decoded& out,
                                          std::vector<uint8_t>& storage);

// Byte building for hand-written wire data.
class Bytes {
 public:
  Bytes& raw(std::initializer_list<int> bytes) {
    for (int b : bytes) v.push_back(static_cast<uint8_t>(b));
    return *this;
  }
  Bytes& zeros(size_t n) {
    v.insert(v.end(), n, uint8_t{0});
    return *this;
  }
  Bytes& text(std::string_view s) {
    v.insert(v.end(), s.begin(), s.end());
    return *this;
  }
  std::vector<uint8_t> v;
};

// Little-endian stores written independently of the library (for patching).
void put_u16(std::vector<uint8_t>& b, size_t at, uint16_t v);
void put_u32(std::vector<uint8_t>& b, size_t at, uint32_t v);
void put_u64(std::vector<uint8_t>& b, size_t at, uint64_t v);

// Largest max_message_bytes used by the suite.
inline constexpr uint64_t kMaxMessage = 1u << 20;

}  // namespace dn::protocol::test
