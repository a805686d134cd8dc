// The fixed 24-byte header: payload limits per type and validation.
#include <algorithm>
#include <stdexcept>
#include <string>

#include "wire.hpp"

namespace dn::protocol {

uint64_t max_payload_bytes(MessageType type, uint64_t max_message_bytes) {
  const uint64_t cap = max_message_bytes > kHeaderSize ? max_message_bytes - kHeaderSize : 0;
  uint64_t limit = 0;
  switch (type) {
    case MessageType::Hello: limit = 4 * 1024; break;
    case MessageType::Welcome: limit = 64 * 1024; break;
    case MessageType::Error: limit = 8 * 1024; break;
    case MessageType::OpenSession: limit = 64 * 1024; break;
    case MessageType::Session: limit = 64 * 1024; break;
    case MessageType::Frame: limit = cap; break;
    case MessageType::Result: limit = cap; break;
    case MessageType::Attach: limit = 8 + 2 + kWatchKeyLength; break;  // session_id, 1.6 watch_key
    case MessageType::Ping: limit = 8; break;
    case MessageType::Pong: limit = 8; break;
    case MessageType::CloseSession: limit = 8; break;
    case MessageType::SessionClosed: limit = 16; break;
    case MessageType::StatsRequest: limit = 0; break;
    case MessageType::Stats: limit = 64 * 1024; break;
    default: return 0;
  }
  return std::min(limit, cap);
}

namespace wire {

void store_header(uint8_t* p, const Header& h) {
  store_u32(p + 0, h.magic);
  p[4] = h.version_major;
  p[5] = h.version_minor;
  store_u16(p + 6, static_cast<uint16_t>(h.type));
  store_u32(p + 8, h.flags);
  store_u32(p + 12, h.payload_length);
  store_u64(p + 16, h.request_id);
}

}  // namespace wire

void set_request_id(std::span<uint8_t> message, uint64_t request_id) {
  if (message.size() < kHeaderSize)
    throw std::invalid_argument("dn::protocol::set_request_id: " + std::to_string(message.size()) +
                                " bytes are not a header");
  wire::store_u64(message.data() + 16, request_id);
}

namespace {
std::string hex32(uint32_t v) {
  static const char* digits = "0123456789ABCDEF";
  std::string s = "0x";
  for (int i = 7; i >= 0; --i) s += digits[(v >> (4 * i)) & 0xF];
  return s;
}
}  // namespace

std::optional<DecodeError> decode_header(std::span<const uint8_t> bytes, uint64_t max_message_bytes,
                                         Header& out) {
  using namespace wire;
  if (bytes.size() < kHeaderSize)
    return DecodeError{ErrorCode::Malformed, "header",
                       "header needs " + std::to_string(kHeaderSize) + " bytes, got " + std::to_string(bytes.size())};
  const uint8_t* p = bytes.data();
  Header h;
  h.magic = load_u32(p + 0);
  h.version_major = p[4];
  h.version_minor = p[5];
  const uint16_t type = load_u16(p + 6);
  h.type = static_cast<MessageType>(type);
  h.flags = load_u32(p + 8);
  h.payload_length = load_u32(p + 12);
  h.request_id = load_u64(p + 16);

  if (h.magic != kMagic)
    return DecodeError{ErrorCode::BadMagic, "header.magic",
                       "magic " + hex32(h.magic) + " is not " + hex32(kMagic) + " (\"DNSV\")"};
  if (h.version_major != kVersionMajor)
    return DecodeError{ErrorCode::UnsupportedVersion, "header.version_major",
                       "protocol version " + std::to_string(h.version_major) + "." + std::to_string(h.version_minor) +
                           " is not supported; major version must be " + std::to_string(kVersionMajor)};
  if (!is_known_type(h.type))
    return DecodeError{ErrorCode::UnknownMessageType, "header.type",
                       "message type " + std::to_string(type) + " is not known"};
  if (h.flags & ~kDefinedHeaderFlags)
    return DecodeError{ErrorCode::ReservedFlags, "header.flags",
                       "reserved header flag bits " + hex32(h.flags & ~kDefinedHeaderFlags) + " are set"};
  if ((h.flags & kFlagNoOutput) && h.type != MessageType::Frame)
    return DecodeError{ErrorCode::ReservedFlags, "header.flags",
                       std::string("flag NO_OUTPUT is only defined for FRAME, found on ") + to_string(h.type)};
  if ((h.flags & kFlagShareInput) && h.type != MessageType::OpenSession)
    return DecodeError{ErrorCode::ReservedFlags, "header.flags",
                       std::string("flag SHARE_INPUT is only defined for OPEN_SESSION, found on ") + to_string(h.type)};
  const uint64_t limit = max_payload_bytes(h.type, max_message_bytes);
  if (h.payload_length > limit)
    return DecodeError{ErrorCode::MessageTooLarge, "header.payload_length",
                       "payload_length " + std::to_string(h.payload_length) + " exceeds the " +
                           std::to_string(limit) + "-byte limit for " + to_string(h.type)};
  out = h;
  return std::nullopt;
}

}  // namespace dn::protocol
