// MessageReader: header -> payload framing over a byte stream. The payload
// buffer is allocated only after decode_header() accepted the header, and is
// exactly payload_length long.
#include "wire.hpp"

namespace dn::protocol {

std::span<uint8_t> MessageReader::writable() {
  if (status_ != Status::NeedMore) return {};
  if (header_filled_ < kHeaderSize) return {header_bytes_ + header_filled_, kHeaderSize - header_filled_};
  return {payload_.data() + payload_filled_, payload_.size() - payload_filled_};
}

MessageReader::Status MessageReader::commit(size_t n) {
  if (n == 0) return status_;
  if (n > writable().size()) {
    // A caller bug, not a peer's: nothing was written where it was told to.
    status_ = Status::Failed;
    error_ = DecodeError{ErrorCode::Internal, "MessageReader::commit",
                         "commit(" + std::to_string(n) + ") exceeds the " + std::to_string(writable().size()) +
                             " writable bytes"};
    return status_;
  }
  if (header_filled_ < kHeaderSize) {
    header_filled_ += n;
    if (header_filled_ < kHeaderSize) return status_;
    Header h;
    if (auto err = decode_header({header_bytes_, kHeaderSize}, max_message_bytes_, h)) {
      error_ = std::move(*err);
      status_ = Status::Failed;
      return status_;
    }
    header_ = h;
    if (header_.payload_length == 0) {
      status_ = Status::Ready;
      return status_;
    }
    payload_ = std::vector<uint8_t>(header_.payload_length);
    return status_;
  }
  payload_filled_ += n;
  if (payload_filled_ == payload_.size()) status_ = Status::Ready;
  return status_;
}

std::vector<uint8_t> MessageReader::take_payload() {
  if (status_ != Status::Ready) return {};
  std::vector<uint8_t> out = std::move(payload_);
  payload_ = {};
  header_filled_ = 0;
  payload_filled_ = 0;
  status_ = Status::NeedMore;
  // header_ keeps the taken message's header until the next header completes.
  return out;
}

}  // namespace dn::protocol
