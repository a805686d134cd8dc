// Encoding and decoding of protocol v1 over byte buffers. Pure functions and
// one small framing state machine; no sockets, no Vulkan.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "dn/protocol/half.hpp"
#include "dn/protocol/messages.hpp"

namespace dn::protocol {

struct DecodeError {
  ErrorCode code = ErrorCode::Malformed;
  std::string field;    // which field was wrong, e.g. "header.magic", "OPEN_SESSION.channels[1].format"
  std::string message;  // human-readable, names the value found and what was expected
};

// Largest payload a message of this type may declare. FRAME and RESULT are
// bounded by the configured maximum message size; control messages by fixed
// small limits, so a header can be rejected before anything is allocated.
uint64_t max_payload_bytes(MessageType type, uint64_t max_message_bytes);

// Appends header + payload of `message` to `out`. `flags` are header flags.
// The payload size is computed first and `out` is reserved once. Whatever is
// written decodes: a message that breaks a rule of docs/protocol.md (string or
// list over its limit, non-finite float, duplicate channel, undefined flag, ...)
// throws std::invalid_argument naming the field, and one the wire cannot
// represent at all (string > 65535 bytes, payload > 4 GiB) throws
// std::length_error; `out` is then left as it was.
void encode(const Message& message, uint64_t request_id, uint32_t flags, std::vector<uint8_t>& out);
std::vector<uint8_t> encode(const Message& message, uint64_t request_id = 0, uint32_t flags = 0);
// Rewrites the request id in the header of an encoded message, so that a
// reply encoded once can answer many requests (the server's WELCOME).
// std::invalid_argument when `message` is shorter than a header.
void set_request_id(std::span<uint8_t> message, uint64_t request_id);

// The same bytes as encode(), without copying plane data: `segments` lists,
// in order, pieces of `scratch` (header and fields) and the caller's plane
// spans, ready for writev()/sendmsg(). The spans stay valid while `scratch`
// and the planes do. Same validation and exceptions as encode().
void encode_segments(const Message& message, uint64_t request_id, uint32_t flags, std::vector<uint8_t>& scratch,
                     std::vector<std::span<const uint8_t>>& segments);

// Where a gathered send stands: the first byte of `segments` not yet sent.
// advance(n) moves past n bytes the socket took; writers build their
// iovecs from remaining(i) for i = segment, segment + 1, ...
struct SegmentCursor {
  size_t segment = 0;
  size_t offset = 0;

  bool done(std::span<const std::span<const uint8_t>> segments) const { return segment >= segments.size(); }
  std::span<const uint8_t> remaining(std::span<const std::span<const uint8_t>> segments, size_t i) const {
    return segments[i].subspan(i == segment ? offset : 0);
  }
  void advance(std::span<const std::span<const uint8_t>> segments, size_t n) {
    while (n > 0 && segment < segments.size()) {
      const size_t left = segments[segment].size() - offset;
      if (n < left) {
        offset += n;
        return;
      }
      n -= left;
      ++segment;
      offset = 0;
    }
  }
};

// Validates and parses a fixed header: magic, version (major must match, any
// minor), known type, reserved flags zero, payload length within
// max_payload_bytes(type, max_message_bytes).
std::optional<DecodeError> decode_header(std::span<const uint8_t> bytes, uint64_t max_message_bytes,
                                         Header& out);

// Parses a payload whose header already passed decode_header. Plane views in
// `out` point into `payload`, which must outlive them. Trailing bytes,
// truncation, out-of-range enums and reserved fields are errors.
std::optional<DecodeError> decode_payload(const Header& header, std::span<const uint8_t> payload,
                                          Message& out);

// Incremental framing for a byte stream: the caller reads straight into
// writable(), then calls commit(n). The header is validated before the
// payload buffer is allocated, and the buffer is exactly payload_length long.
class MessageReader {
 public:
  enum class Status { NeedMore, Ready, Failed };

  explicit MessageReader(uint64_t max_message_bytes) : max_message_bytes_(max_message_bytes) {}
  // Changes the limit for headers not yet read (a server lowers it until a
  // peer has a session whose frames need more).
  void set_max_message_bytes(uint64_t max_message_bytes) { max_message_bytes_ = max_message_bytes; }

  std::span<uint8_t> writable();
  Status commit(size_t n);
  Status status() const { return status_; }

  // Valid when status() == Ready. take_payload() resets the reader for the next message;
  // header() keeps describing the taken message until the next header completes.
  const Header& header() const { return header_; }
  std::vector<uint8_t> take_payload();
  // Valid when status() == Failed. The stream cannot be resynchronised after this.
  const DecodeError& error() const { return error_; }
  // Bytes of the current message received so far (header + payload).
  uint64_t bytes_buffered() const { return header_filled_ + payload_filled_; }
  // The current message's size (header + payload) once its header is read, else 0.
  uint64_t bytes_declared() const { return header_filled_ == kHeaderSize ? kHeaderSize + header_.payload_length : 0; }

  // Admission of a payload, asked once its header is read (a server's
  // receive budget): when it returns false the payload is read and dropped
  // (the stream stays in step), the message comes out Ready with refused()
  // true and take_payload() empty.
  void set_admission(std::function<bool(const Header&)> admit) { admit_ = std::move(admit); }
  bool refused() const { return refused_; }

 private:
  uint64_t max_message_bytes_;
  std::function<bool(const Header&)> admit_;
  bool refused_ = false;
  std::vector<uint8_t> discard_;  // where a refused payload is read to
  Status status_ = Status::NeedMore;
  uint8_t header_bytes_[kHeaderSize] = {};
  size_t header_filled_ = 0;
  Header header_{};
  std::vector<uint8_t> payload_;
  size_t payload_filled_ = 0;
  DecodeError error_{};
};

}  // namespace dn::protocol
