// MessageReader: header -> payload framing over a byte stream. The payload
// buffer is reserved only after decode_header() accepted the header, exactly
// payload_length long, and filled in steps of kGrowBytes as bytes arrive: a
// header alone makes no page resident (reserve() does not touch the memory;
// resize() within it zero-fills only the next step).
#include <algorithm>

#include "wire.hpp"

namespace dn::protocol {
namespace {
constexpr size_t kGrowBytes = 4u << 20;     // payload made writable per step
constexpr size_t kDiscardBytes = 64u << 10;  // a refused payload is read through this
}  // namespace

std::span<uint8_t> MessageReader::writable() {
  if (status_ != Status::NeedMore) return {};
  if (header_filled_ < kHeaderSize) return {header_bytes_ + header_filled_, kHeaderSize - header_filled_};
  if (refused_) {
    const size_t left = header_.payload_length - payload_filled_;
    return {discard_.data(), std::min(left, discard_.size())};
  }
  if (payload_filled_ == payload_.size())
    payload_.resize(payload_.size() + std::min<size_t>(kGrowBytes, header_.payload_length - payload_.size()));
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
    if (admit_ && !admit_(header_)) {
      refused_ = true;
      discard_.resize(kDiscardBytes);
      return status_;
    }
    payload_ = {};
    payload_.reserve(header_.payload_length);
    return status_;
  }
  payload_filled_ += n;
  if (payload_filled_ == header_.payload_length) status_ = Status::Ready;
  return status_;
}

std::vector<uint8_t> MessageReader::take_payload() {
  if (status_ != Status::Ready) return {};
  std::vector<uint8_t> out = std::move(payload_);
  payload_ = {};
  refused_ = false;
  header_filled_ = 0;
  payload_filled_ = 0;
  status_ = Status::NeedMore;
  // header_ keeps the taken message's header until the next header completes.
  return out;
}

}  // namespace dn::protocol
