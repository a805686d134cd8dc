// encode(): one layout description per message, run twice — once by a
// counting sink to get the exact payload size (so the output is reserved
// once, frames are ~100 MB), once by the writing sink.
#include <limits>
#include <stdexcept>

#include "wire.hpp"

namespace dn::protocol {
namespace {

using wire::Writer;

// Counts bytes and rejects what the wire cannot represent at all (lengths
// and counts are u16, payload_length is u32). Semantic limits are checked
// afterwards by decoding the encoded payload.
class Counter {
 public:
  void u8(uint8_t) { n_ += 1; }
  void u16(uint16_t) { n_ += 2; }
  void u32(uint32_t) { n_ += 4; }
  void u64(uint64_t) { n_ += 8; }
  void f32(float) { n_ += 4; }
  void f64(double) { n_ += 8; }
  void bytes(std::span<const uint8_t> b) { n_ += b.size(); }
  void str(std::string_view s) {
    if (s.size() > std::numeric_limits<uint16_t>::max())
      throw std::length_error("dn::protocol::encode: string of " + std::to_string(s.size()) +
                              " bytes does not fit a u16 length");
    n_ += 2 + s.size();
  }
  void zeros(size_t n) { n_ += n; }
  uint64_t size() const { return n_; }

 private:
  uint64_t n_ = 0;
};

// Writes like Writer but leaves plane bytes where they are: each one becomes
// its own segment, so a sender can writev() the caller's planes directly.
class Gatherer {
 public:
  explicit Gatherer(std::vector<uint8_t>& scratch) : scratch_(scratch), writer_(scratch) {}
  void u8(uint8_t v) { writer_.u8(v); }
  void u16(uint16_t v) { writer_.u16(v); }
  void u32(uint32_t v) { writer_.u32(v); }
  void u64(uint64_t v) { writer_.u64(v); }
  void f32(float v) { writer_.f32(v); }
  void f64(double v) { writer_.f64(v); }
  void str(std::string_view v) { writer_.str(v); }
  void zeros(size_t n) { writer_.zeros(n); }
  void bytes(std::span<const uint8_t> b) {
    close_scratch_piece();
    pieces_.push_back({true, 0, b.size(), b.data()});
  }
  // Spans are taken at the end: scratch may reallocate while it grows.
  void finish(std::vector<std::span<const uint8_t>>& segments) {
    close_scratch_piece();
    for (const Piece& p : pieces_)
      if (p.size) segments.emplace_back(p.external ? p.data : scratch_.data() + p.offset, p.size);
  }

 private:
  struct Piece {
    bool external;
    size_t offset, size;
    const uint8_t* data;
  };
  void close_scratch_piece() {
    if (scratch_.size() > open_from_) pieces_.push_back({false, open_from_, scratch_.size() - open_from_, nullptr});
    open_from_ = scratch_.size();
  }
  std::vector<uint8_t>& scratch_;
  Writer writer_;
  std::vector<Piece> pieces_;
  size_t open_from_ = 0;
};

template <class S>
void count(S& s, size_t n) {
  if constexpr (std::is_same_v<S, Counter>) {
    if (n > std::numeric_limits<uint16_t>::max())
      throw std::length_error("dn::protocol::encode: list of " + std::to_string(n) +
                              " entries does not fit a u16 count");
  }
  s.u16(static_cast<uint16_t>(n));
}

template <class S>
void put_channels(S& s, const std::vector<ChannelDecl>& channels) {
  count(s, channels.size());
  for (const auto& c : channels) {
    s.u8(static_cast<uint8_t>(c.id));
    s.u8(static_cast<uint8_t>(c.format));
  }
}

template <class S>
void put_planes(S& s, const std::vector<PlaneView>& planes) {
  count(s, planes.size());
  for (const auto& p : planes) {
    s.u8(static_cast<uint8_t>(p.id));
    s.u8(static_cast<uint8_t>(p.format));
    s.u16(0);  // reserved
    s.u64(p.bytes.size());
    s.bytes(p.bytes);
  }
}

template <class S>
void put_mat(S& s, const Mat4& m) {
  for (float v : m) s.f32(v);
}

template <class S>
struct Put {
  S& s;
  void operator()(const Hello& m) {
    s.u32(m.capabilities);
    s.str(m.client_name);
    s.str(m.auth_token);
  }
  void operator()(const Welcome& m) {
    s.str(m.server_version);
    s.str(m.device_name);
    s.u64(m.limits.max_message_bytes);
    s.u64(m.limits.max_session_bytes);
    s.u32(m.limits.max_sessions);
    s.u32(m.limits.max_width);
    s.u32(m.limits.max_height);
    s.u32(m.limits.max_frames_in_flight);
    count(s, m.pipelines.size());
    for (const auto& p : m.pipelines) {
      s.str(p.name);
      s.u64(p.required_channels);
      s.u64(p.optional_channels);
    }
    if (!m.has_parameters) return;  // the 1.0 payload, for a 1.0 client
    // 1.1: appended after every 1.0 field, one list per pipeline, same order.
    count(s, m.pipelines.size());
    for (const auto& p : m.pipelines) {
      count(s, p.parameters.size());
      for (const auto& q : p.parameters) {
        s.str(q.name);
        s.f64(q.default_value);
        s.f64(q.min_value);
        s.f64(q.max_value);
        s.u8(q.integer ? 1 : 0);
        s.str(q.description);
      }
    }
  }
  void operator()(const Error& m) {
    s.u32(static_cast<uint32_t>(m.code));
    s.str(m.field);
    s.str(m.message);
  }
  void operator()(const OpenSession& m) {
    s.u32(m.width);
    s.u32(m.height);
    s.str(m.pipeline);
    s.u8(static_cast<uint8_t>(m.output_format));
    s.u8(0);  // reserved
    count(s, m.parameters.size());
    for (const auto& p : m.parameters) {
      s.str(p.name);
      s.f64(p.value);
    }
    put_channels(s, m.channels);
  }
  void operator()(const Session& m) {
    s.u64(m.session_id);
    s.u32(m.width);
    s.u32(m.height);
    s.str(m.pipeline);
    s.u8(static_cast<uint8_t>(m.output_format));
    s.u8(m.read_only ? 1 : 0);
    s.u64(m.device_bytes);
    put_channels(s, m.channels);
    if (m.watch_key) s.str(*m.watch_key);  // 1.6, for a peer that knows it
    if (m.watch_url) s.str(*m.watch_url);  // 1.8, likewise
    if (m.pipeline_reason) s.str(*m.pipeline_reason);  // 1.10, likewise
  }
  void operator()(const Frame& m) {
    const FrameInfo& f = m.info;
    s.u64(f.session_id);
    s.u64(f.frame_index);
    s.u32(f.flags);
    s.u8(static_cast<uint8_t>(f.motion));
    s.zeros(3);  // reserved
    put_mat(s, f.view);
    put_mat(s, f.projection);
    put_mat(s, f.prev_view);
    put_mat(s, f.prev_projection);
    for (float v : f.jitter) s.f32(v);
    for (float v : f.prev_jitter) s.f32(v);
    put_planes(s, m.planes);
  }
  void operator()(const Result& m) {
    s.u64(m.session_id);
    s.u64(m.frame_index);
    count(s, m.timings.size());
    for (const auto& t : m.timings) {
      s.str(t.name);
      s.f64(t.milliseconds);
    }
    put_planes(s, m.planes);
    if (m.samples) {  // 1.9, for a peer that knows it
      s.u8(m.samples->counted ? 1 : 0);
      s.u32(m.samples->min);
      s.u32(m.samples->median);
    }
  }
  void operator()(const Attach& m) {
    s.u64(m.session_id);
    if (m.watch_key) s.str(*m.watch_key);  // 1.6, for a server that knows it
  }
  void operator()(const Ping& m) { s.u64(m.payload); }
  void operator()(const Pong& m) { s.u64(m.payload); }
  void operator()(const CloseSession& m) { s.u64(m.session_id); }
  void operator()(const SessionClosed& m) {
    s.u64(m.session_id);
    s.u64(m.frames_processed);
  }
  void operator()(const StatsRequest&) {}
  void operator()(const Stats& m) {
    count(s, m.values.size());
    for (const auto& v : m.values) {
      s.str(v.name);
      s.f64(v.value);
    }
  }
};

// The minor version whose fields the payload holds: the header always says
// kVersionMinor (the sender's own), but a WELCOME for a 1.0 client stops
// after the 1.0 fields (docs/protocol.md §10), so it is checked as 1.0; a
// SESSION or ATTACH without its watch key is a 1.5 payload, a SESSION
// without its watch URL a 1.7 one, a RESULT without sample counts a 1.8 one.
uint8_t payload_minor(const Message& message) {
  if (const auto* w = std::get_if<Welcome>(&message); w && !w->has_parameters) return 0;
  if (const auto* s = std::get_if<Session>(&message); s && !s->watch_key) return kWatchKeyMinor - 1;
  if (const auto* s = std::get_if<Session>(&message); s && !s->watch_url) return kWatchUrlMinor - 1;
  if (const auto* s = std::get_if<Session>(&message); s && !s->pipeline_reason) return kAutoMinor - 1;
  if (const auto* a = std::get_if<Attach>(&message); a && !a->watch_key) return kWatchKeyMinor - 1;
  if (const auto* r = std::get_if<Result>(&message); r && !r->samples) return kSamplesMinor - 1;
  return kVersionMinor;
}

void check_welcome_parameters(const Message& message) {
  const auto* w = std::get_if<Welcome>(&message);
  if (!w || w->has_parameters) return;
  for (size_t i = 0; i < w->pipelines.size(); ++i)
    if (!w->pipelines[i].parameters.empty())
      throw std::invalid_argument("dn::protocol::encode: WELCOME.pipelines[" + std::to_string(i) +
                                  "] has parameters but has_parameters is false, so they would not be sent");
}

}  // namespace

void encode(const Message& message, uint64_t request_id, uint32_t flags, std::vector<uint8_t>& out) {
  const MessageType type = type_of(message);
  if (flags & ~kDefinedHeaderFlags)
    throw std::invalid_argument("dn::protocol::encode: header.flags has reserved bits set");
  if ((flags & kFlagNoOutput) && type != MessageType::Frame)
    throw std::invalid_argument(std::string("dn::protocol::encode: header.flags NO_OUTPUT is only defined for FRAME, not ") +
                                to_string(type));
  if ((flags & kFlagShareInput) && type != MessageType::OpenSession)
    throw std::invalid_argument(
        std::string("dn::protocol::encode: header.flags SHARE_INPUT is only defined for OPEN_SESSION, not ") +
        to_string(type));

  check_welcome_parameters(message);
  if (const auto* s = std::get_if<Session>(&message); s && s->watch_url && !s->watch_key)
    throw std::invalid_argument("dn::protocol::encode: SESSION.watch_url (1.8) needs watch_key (1.6) before it");
  if (const auto* s = std::get_if<Session>(&message); s && s->pipeline_reason && !s->watch_url)
    throw std::invalid_argument("dn::protocol::encode: SESSION.pipeline_reason (1.10) needs watch_url (1.8) before it");

  Counter counter;
  std::visit(Put<Counter>{counter}, message);
  const uint64_t payload_size = counter.size();
  if (payload_size > std::numeric_limits<uint32_t>::max())
    throw std::length_error("dn::protocol::encode: payload of " + std::to_string(payload_size) +
                            " bytes does not fit the u32 payload_length");
  // A header over its type's fixed limit is refused before its payload is read
  // (a WELCOME 1.1 with long parameter tables can get there).
  const uint64_t type_limit = max_payload_bytes(type, std::numeric_limits<uint64_t>::max());
  if (payload_size > type_limit)
    throw std::invalid_argument("dn::protocol::encode: header.payload_length " + std::to_string(payload_size) +
                                " exceeds the " + std::to_string(type_limit) + "-byte limit for " + to_string(type));

  Header h;
  h.type = type;
  h.flags = flags;
  h.payload_length = static_cast<uint32_t>(payload_size);
  h.request_id = request_id;

  const size_t start = out.size();
  out.reserve(start + kHeaderSize + payload_size);
  out.resize(start + kHeaderSize);
  wire::store_header(out.data() + start, h);
  Writer writer(out);
  std::visit(Put<Writer>{writer}, message);

  // Whatever encode() writes, decode_payload() accepts: a message that breaks
  // a rule (string too long, NaN, duplicate channel, ...) is a bug in the
  // sender and is reported here rather than by the peer.
  Message check;
  const std::span<const uint8_t> payload(out.data() + start + kHeaderSize, payload_size);
  Header as_read = h;
  as_read.version_minor = payload_minor(message);
  if (auto err = decode_payload(as_read, payload, check)) {
    out.resize(start);
    throw std::invalid_argument("dn::protocol::encode: " + err->field + ": " + err->message);
  }
}

void encode_segments(const Message& message, uint64_t request_id, uint32_t flags, std::vector<uint8_t>& scratch,
                     std::vector<std::span<const uint8_t>>& segments) {
  // Validate everything but the plane bytes (which the decoder only counts) by
  // encoding the message with empty planes: cheap, and the same rules as encode().
  Message skeleton = message;
  std::visit(
      [](auto& m) {
        if constexpr (requires { m.planes; })
          for (auto& p : m.planes) p.bytes = {};
      },
      skeleton);
  scratch.clear();
  encode(skeleton, request_id, flags, scratch);

  Counter counter;
  std::visit(Put<Counter>{counter}, message);
  if (counter.size() > std::numeric_limits<uint32_t>::max())
    throw std::length_error("dn::protocol::encode: payload of " + std::to_string(counter.size()) +
                            " bytes does not fit the u32 payload_length");
  Header h;
  h.type = type_of(message);
  h.flags = flags;
  h.payload_length = static_cast<uint32_t>(counter.size());
  h.request_id = request_id;
  scratch.clear();
  scratch.resize(kHeaderSize);
  wire::store_header(scratch.data(), h);
  Gatherer gatherer(scratch);
  std::visit(Put<Gatherer>{gatherer}, message);
  segments.clear();
  gatherer.finish(segments);
}

std::vector<uint8_t> encode(const Message& message, uint64_t request_id, uint32_t flags) {
  std::vector<uint8_t> out;
  encode(message, request_id, flags, out);
  return out;
}

}  // namespace dn::protocol
