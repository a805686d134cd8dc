// MessageReader: framing over a byte stream, fed in every chunking, and
// header-before-allocation. This file replaces the global operator new to
// observe what the reader allocates.
#include <gtest/gtest.h>

#include <algorithm>

#include <atomic>
#include <cstdlib>
#include <new>

#include "support.hpp"

namespace {
// Largest single allocation since the last reset (all threads).
std::atomic<size_t> g_largest_allocation{0};
std::atomic<size_t> g_allocations{0};

void* counted_alloc(size_t n) {
  size_t prev = g_largest_allocation.load();
  while (n > prev && !g_largest_allocation.compare_exchange_weak(prev, n)) {
  }
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void reset_allocation_stats() {
  g_largest_allocation = 0;
  g_allocations = 0;
}
}  // namespace

void* operator new(size_t n) { return counted_alloc(n); }
void* operator new[](size_t n) { return counted_alloc(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }

namespace dn::protocol::test {
namespace {

struct Received {
  Header header;
  std::vector<uint8_t> payload;
};

// Feeds `stream` to a reader in chunks chosen by `next_chunk` (never more
// than writable()), collecting every complete message.
template <class Chunker>
std::vector<Received> feed(const std::vector<uint8_t>& stream, uint64_t max_message, Chunker next_chunk,
                           MessageReader::Status* final_status = nullptr) {
  MessageReader reader(max_message);
  std::vector<Received> out;
  size_t pos = 0;
  while (pos < stream.size()) {
    auto w = reader.writable();
    if (w.empty()) break;
    const size_t n = std::min({w.size(), stream.size() - pos, std::max<size_t>(1, next_chunk())});
    std::copy_n(stream.begin() + pos, n, w.begin());
    pos += n;
    auto status = reader.commit(n);
    if (status == MessageReader::Status::Failed) break;
    while (reader.status() == MessageReader::Status::Ready) {
      Received r;
      r.header = reader.header();
      r.payload = reader.take_payload();
      out.push_back(std::move(r));
    }
  }
  if (final_status) *final_status = reader.status();
  return out;
}

struct Stream {
  std::vector<OwnedMessage> messages;
  std::vector<uint64_t> request_ids;
  std::vector<uint8_t> bytes;
};

Stream make_stream(std::mt19937& rng, int count) {
  Stream s;
  for (int i = 0; i < count; ++i) {
    const MessageType type = kAllTypes[rng() % std::size(kAllTypes)];
    s.messages.push_back(random_message(type, rng, 200));
    s.request_ids.push_back(rng());
    encode(s.messages.back().message, s.request_ids.back(), 0, s.bytes);
  }
  return s;
}

void expect_stream_decoded(const Stream& s, const std::vector<Received>& got) {
  ASSERT_EQ(got.size(), s.messages.size());
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].header.request_id, s.request_ids[i]);
    EXPECT_EQ(got[i].payload.size(), got[i].header.payload_length);
    Message m;
    auto err = decode_payload(got[i].header, got[i].payload, m);
    ASSERT_FALSE(err) << err->field << ": " << err->message;
    EXPECT_EQ(diff(s.messages[i].message, m), "") << "message " << i;
  }
}

TEST(MessageReader, ChunkingDoesNotMatter) {
  std::mt19937 rng(5);
  const Stream s = make_stream(rng, 60);
  const auto whole = feed(s.bytes, kMaxMessage, [] { return SIZE_MAX; });
  expect_stream_decoded(s, whole);
  const auto bytewise = feed(s.bytes, kMaxMessage, [] { return size_t{1}; });
  expect_stream_decoded(s, bytewise);
  for (int seed = 0; seed < 5; ++seed) {
    std::mt19937 chunk_rng(seed);
    const auto chunked =
        feed(s.bytes, kMaxMessage, [&] { return std::uniform_int_distribution<size_t>(1, 40)(chunk_rng); });
    expect_stream_decoded(s, chunked);
  }
}

TEST(MessageReader, ZeroLengthPayloadIsReadyAfterHeader) {
  const auto bytes = encode(StatsRequest{}, 42);
  ASSERT_EQ(bytes.size(), 24u);
  MessageReader reader(kMaxMessage);
  auto w = reader.writable();
  ASSERT_EQ(w.size(), 24u);
  std::copy_n(bytes.begin(), 23, w.begin());
  EXPECT_EQ(reader.commit(23), MessageReader::Status::NeedMore);
  ASSERT_EQ(reader.writable().size(), 1u);
  reader.writable()[0] = bytes[23];
  EXPECT_EQ(reader.commit(1), MessageReader::Status::Ready);
  EXPECT_TRUE(reader.writable().empty());
  EXPECT_EQ(reader.header().type, MessageType::StatsRequest);
  EXPECT_EQ(reader.header().request_id, 42u);
  EXPECT_TRUE(reader.take_payload().empty());
  EXPECT_EQ(reader.status(), MessageReader::Status::NeedMore);
  EXPECT_EQ(reader.bytes_buffered(), 0u);
  // The header of the taken message stays readable until the next one completes.
  EXPECT_EQ(reader.header().request_id, 42u);
}

TEST(MessageReader, PayloadBufferIsExactlyPayloadLength) {
  const uint8_t plane[1000] = {};
  Frame f;
  f.planes = {{ChannelId::Radiance, Format::F32, plane}};
  const auto bytes = encode(f);
  const size_t payload_length = bytes.size() - 24;
  MessageReader reader(kMaxMessage);
  std::copy_n(bytes.begin(), 24, reader.writable().begin());
  reset_allocation_stats();
  EXPECT_EQ(reader.commit(24), MessageReader::Status::NeedMore);
  EXPECT_EQ(g_allocations.load(), 1u);
  EXPECT_EQ(g_largest_allocation.load(), payload_length);
  EXPECT_EQ(reader.writable().size(), payload_length);
  EXPECT_EQ(reader.bytes_buffered(), 24u);
  std::copy(bytes.begin() + 24, bytes.end(), reader.writable().begin());
  EXPECT_EQ(reader.commit(payload_length), MessageReader::Status::Ready);
  EXPECT_EQ(reader.bytes_buffered(), bytes.size());
  auto payload = reader.take_payload();
  EXPECT_EQ(payload.size(), payload_length);
  EXPECT_EQ(payload.capacity(), payload_length);
}

// A header alone must not make the server's memory resident: the
// payload is reserved (untouched pages cost no RSS) and made writable, and
// zero-filled, one step (4 MiB) at a time as bytes arrive.
TEST(MessageReader, LargePayloadBecomesWritableStepByStep) {
  const uint32_t payload_length = 64u << 20;
  std::vector<uint8_t> header = Bytes{}.raw({0x44, 0x4E, 0x53, 0x56, 1, 0}).zeros(18).v;
  put_u16(header, 6, 6);  // FRAME
  put_u32(header, 12, payload_length);
  MessageReader reader(1ull << 30);
  std::copy(header.begin(), header.end(), reader.writable().begin());
  ASSERT_EQ(reader.commit(24), MessageReader::Status::NeedMore);
  EXPECT_EQ(reader.bytes_declared(), 24u + payload_length);
  size_t steps = 0, filled = 0;
  while (filled < payload_length) {
    std::span<uint8_t> w = reader.writable();
    ASSERT_GT(w.size(), 0u);
    EXPECT_LE(w.size(), size_t{4} << 20) << "more than one step writable at byte " << filled;
    filled += w.size();
    ++steps;
    reader.commit(w.size());
  }
  EXPECT_EQ(steps, payload_length / (4u << 20));
  EXPECT_EQ(reader.status(), MessageReader::Status::Ready);
  EXPECT_EQ(reader.take_payload().size(), payload_length);
}

// A payload the owner's admission refuses (a server's receive budget) is read
// and dropped: the stream stays in step and the next message is whole.
TEST(MessageReader, RefusedPayloadIsDroppedAndTheStreamStaysInStep) {
  const std::vector<uint8_t> plane(200000, 7);
  Frame f;
  f.planes = {{ChannelId::Radiance, Format::F32, plane}};
  std::vector<uint8_t> stream = encode(f, 5);
  const std::vector<uint8_t> stats = encode(StatsRequest{}, 6);
  stream.insert(stream.end(), stats.begin(), stats.end());
  MessageReader reader(kMaxMessage);
  std::vector<uint64_t> asked;
  reader.set_admission([&](const Header& h) {
    asked.push_back(h.payload_length);
    return h.payload_length < 100000;
  });
  std::vector<std::pair<uint64_t, bool>> got;  // request id, refused
  size_t pos = 0;
  while (pos < stream.size()) {
    std::span<uint8_t> w = reader.writable();
    const size_t n = std::min(w.size(), stream.size() - pos);
    std::copy_n(stream.begin() + pos, n, w.begin());
    pos += n;
    if (reader.commit(n) == MessageReader::Status::Ready) {
      const bool refused = reader.refused();
      got.emplace_back(reader.header().request_id, refused);
      EXPECT_TRUE(reader.take_payload().empty() || !refused);
    }
  }
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0], std::make_pair(uint64_t{5}, true));
  EXPECT_EQ(got[1], std::make_pair(uint64_t{6}, false));
  EXPECT_EQ(asked.size(), 1u) << "an empty payload needs no admission";
}

TEST(MessageReader, OversizeHeaderFailsBeforeAnyAllocation) {
  struct Case {
    uint16_t type;
    uint32_t length;
    ErrorCode code;
  };
  for (const Case c : {Case{1, 70000, ErrorCode::MessageTooLarge},            // HELLO over 4 KiB
                       Case{6, 0xFFFFFFFFu, ErrorCode::MessageTooLarge},      // FRAME over max_message_bytes
                       Case{999, 0xFFFFFFFFu, ErrorCode::UnknownMessageType}}) {
    std::vector<uint8_t> header = Bytes{}.raw({0x44, 0x4E, 0x53, 0x56, 1, 0}).zeros(18).v;
    put_u16(header, 6, c.type);
    put_u32(header, 12, c.length);
    MessageReader reader(kMaxMessage);
    reset_allocation_stats();
    for (size_t i = 0; i < 24; ++i) {
      auto w = reader.writable();
      ASSERT_FALSE(w.empty());
      w[0] = header[i];
      reader.commit(1);
    }
    EXPECT_LT(g_largest_allocation.load(), 1024u) << "payload allocated for a rejected header";
    EXPECT_EQ(reader.status(), MessageReader::Status::Failed);
    EXPECT_EQ(reader.error().code, c.code);
    EXPECT_FALSE(reader.error().field.empty());
    EXPECT_EQ(reader.bytes_buffered(), 24u);
    EXPECT_TRUE(reader.writable().empty());
    // Nothing more is accepted: the stream cannot be resynchronised.
    EXPECT_EQ(reader.commit(0), MessageReader::Status::Failed);
    EXPECT_TRUE(reader.take_payload().empty());
  }
}

TEST(MessageReader, BadMagicFailsAfterTheHeader) {
  std::vector<uint8_t> junk(100, 'G');
  MessageReader::Status status;
  auto got = feed(junk, kMaxMessage, [] { return size_t{7}; }, &status);
  EXPECT_TRUE(got.empty());
  EXPECT_EQ(status, MessageReader::Status::Failed);
}

TEST(MessageReader, CommitBeyondWritableIsACallerError) {
  MessageReader reader(kMaxMessage);
  EXPECT_EQ(reader.commit(25), MessageReader::Status::Failed);
  EXPECT_EQ(reader.error().code, ErrorCode::Internal);
}

TEST(MessageReader, MessagesAfterAFailureAreNotDelivered) {
  std::vector<uint8_t> stream = encode(Ping{1}, 1);
  auto bad = encode(Ping{2}, 2);
  bad[4] = 2;  // major 2
  stream.insert(stream.end(), bad.begin(), bad.end());
  encode(Ping{3}, 3, 0, stream);
  MessageReader::Status status;
  auto got = feed(stream, kMaxMessage, [] { return SIZE_MAX; }, &status);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].header.request_id, 1u);
  EXPECT_EQ(status, MessageReader::Status::Failed);
}

}  // namespace
}  // namespace dn::protocol::test
