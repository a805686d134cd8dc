// libFuzzer target for dn_protocol.
//
// Input layout:
//   first byte < 14: the rest is the payload of message type (first byte + 1),
//                    given straight to decode_payload (no header limits);
//   otherwise:       the whole input is a byte stream fed to MessageReader.
// Properties checked (a violation aborts):
//   - nothing crashes, reads out of bounds or trips UBSan;
//   - every DecodeError names a field and a reason;
//   - feeding the stream in small chunks gives the same messages as one feed;
//   - whatever decodes at the current minor version re-encodes to exactly the
//     input bytes (the encoding is canonical), and encode() never throws for it;
//   - the re-encoding of anything that decodes is read back, as the version the
//     input was written in (a 1.0 WELCOME re-encodes as the 1.0 payload a 1.1
//     server sends to a 1.0 client), and is a fixed point of decode + encode;
//   - under a smaller size limit and a receive-budget admission (both chosen
//     from the input, as a server lowers them per connection), the reader
//     delivers a prefix of the same messages, refused ones empty and in step,
//     and stops only with MessageTooLarge or the unlimited run's own error.
//
// Built as `protocol_fuzz` (clang, -fsanitize=fuzzer) when DN_BUILD_FUZZ=ON, and
// always as `protocol_fuzz_replay` (with replay_main.cpp), which runs files or
// directories of inputs given on the command line (e.g. tests/fuzz/corpus).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>
#include <vector>

#include "dn/protocol/codec.hpp"

using namespace dn::protocol;

namespace {

constexpr uint64_t kMaxMessage = 1u << 20;

[[noreturn]] void violated(const char* what) {
  std::fprintf(stderr, "protocol_fuzz: property violated: %s\n", what);
  std::abort();
}

void check_error(const DecodeError& e) {
  if (e.field.empty()) violated("DecodeError without a field");
  if (e.message.empty()) violated("DecodeError without a message");
}

// Decodes one payload; on success checks the canonical re-encoding.
void check_payload(const Header& h, std::span<const uint8_t> payload) {
  Message m;
  if (auto err = decode_payload(h, payload, m)) {
    check_error(*err);
    return;
  }
  if (type_of(m) != h.type) violated("decoded message has another type");
  const std::vector<uint8_t> again = encode(m, h.request_id, h.flags);
  if (again.size() < kHeaderSize) violated("encode wrote less than a header");
  const std::span<const uint8_t> again_payload = std::span(again).subspan(kHeaderSize);
  if (h.version_minor == kVersionMinor) {
    if (again_payload.size() != payload.size() ||
        !std::equal(again_payload.begin(), again_payload.end(), payload.begin()))
      violated("decode then encode does not reproduce the payload");
  }
  // Either way the re-encoding decodes and is a fixed point.
  Header h2;
  if (decode_header(again, UINT64_MAX, h2)) violated("re-encoded header does not decode");
  h2.version_minor = std::min(h.version_minor, kVersionMinor);
  Message m2;
  if (decode_payload(h2, again_payload, m2)) violated("re-encoded payload does not decode");
  if (encode(m2, h2.request_id, h2.flags) != again) violated("encode is not a fixed point");
}

struct Got {
  uint8_t header[kHeaderSize];
  std::vector<uint8_t> payload;
  bool refused = false;
};

// The reader over `data`: limit `max_message`, payloads above `refuse_above`
// refused by its admission (UINT64_MAX: no admission).
std::vector<Got> feed(std::span<const uint8_t> data, bool small_chunks, MessageReader::Status& final_status,
                      DecodeError& final_error, uint64_t max_message = kMaxMessage, uint64_t refuse_above = UINT64_MAX) {
  MessageReader reader(max_message);
  if (refuse_above != UINT64_MAX)
    reader.set_admission([refuse_above](const Header& h) { return h.payload_length <= refuse_above; });
  std::vector<Got> got;
  size_t pos = 0, chunk = 0;
  while (pos < data.size()) {
    auto w = reader.writable();
    if (w.empty()) violated("writable() empty while the reader needs more");
    size_t n = std::min(w.size(), data.size() - pos);
    if (small_chunks) n = std::min(n, 1 + (chunk++ % 17));
    std::memcpy(w.data(), data.data() + pos, n);
    pos += n;
    if (reader.commit(n) == MessageReader::Status::Failed) break;
    if (reader.status() == MessageReader::Status::Ready) {
      Got g;
      const Header& h = reader.header();
      // Keep the raw header by re-deriving it from the consumed bytes.
      const size_t start = pos - (kHeaderSize + h.payload_length);
      std::memcpy(g.header, data.data() + start, kHeaderSize);
      g.refused = reader.refused();
      g.payload = reader.take_payload();
      if (g.refused ? !g.payload.empty() : g.payload.size() != h.payload_length)
        violated("payload size differs from payload_length (or a refused payload is not empty)");
      got.push_back(std::move(g));
    }
  }
  final_status = reader.status();
  if (final_status == MessageReader::Status::Failed) {
    final_error = reader.error();
    check_error(final_error);
  }
  return got;
}

void fuzz_stream(std::span<const uint8_t> data) {
  MessageReader::Status s1, s2;
  DecodeError e1, e2;
  const auto whole = feed(data, false, s1, e1);
  const auto chunked = feed(data, true, s2, e2);
  if (s1 != s2 || whole.size() != chunked.size()) violated("chunking changed the framing");
  if (s1 == MessageReader::Status::Failed && (e1.code != e2.code || e1.field != e2.field))
    violated("chunking changed the framing error");
  for (size_t i = 0; i < whole.size(); ++i) {
    if (std::memcmp(whole[i].header, chunked[i].header, kHeaderSize) != 0 || whole[i].payload != chunked[i].payload)
      violated("chunking changed a message");
    Header h;
    if (auto err = decode_header(whole[i].header, kMaxMessage, h)) violated("reader delivered a bad header");
    check_payload(h, whole[i].payload);
  }
  // A lower limit and an admission, as a server sets them per connection.
  constexpr uint64_t kLimits[] = {kHeaderSize, 64, 4096, 65536};
  constexpr uint64_t kRefuseAbove[] = {0, 16, 1024, UINT64_MAX};
  const uint64_t limit = kLimits[data.size() % 4], refuse_above = kRefuseAbove[data.back() % 4];
  MessageReader::Status s3;
  DecodeError e3;
  const auto limited = feed(data, (data.size() & 4) != 0, s3, e3, limit, refuse_above);
  if (limited.size() > whole.size()) violated("a lower limit delivered more messages");
  for (size_t i = 0; i < limited.size(); ++i) {
    if (std::memcmp(limited[i].header, whole[i].header, kHeaderSize) != 0) violated("a lower limit changed a header");
    Header h;
    decode_header(whole[i].header, kMaxMessage, h);
    const bool refuse = h.payload_length > 0 && h.payload_length > refuse_above;
    if (limited[i].refused != refuse) violated("admission refused the wrong payload");
    if (!refuse && limited[i].payload != whole[i].payload) violated("a lower limit changed a payload");
  }
  if (limited.size() < whole.size() || s3 != s1) {
    if (s3 != MessageReader::Status::Failed) violated("a lower limit stopped without an error");
    if (e3.code != ErrorCode::MessageTooLarge && !(s1 == MessageReader::Status::Failed && e3.code == e1.code))
      violated("a lower limit stopped with an error other than MessageTooLarge");
  }
}

void fuzz_payload(MessageType type, std::span<const uint8_t> payload) {
  // A payload over its type's limit never gets past the header check.
  if (payload.size() > max_payload_bytes(type, UINT64_MAX)) return;
  Header h;
  h.type = type;
  h.payload_length = static_cast<uint32_t>(payload.size());
  check_payload(h, payload);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::span<const uint8_t> input(data, size);
  if (data[0] < 14)
    fuzz_payload(static_cast<MessageType>(data[0] + 1), input.subspan(1));
  else
    fuzz_stream(input);
  return 0;
}
