// decode_payload(): one parser per message type over the bounds-checked
// wire::Reader. Field names follow docs/protocol.md ("OPEN_SESSION.channels[3].format").
#include <cmath>
#include <string>

#include "wire.hpp"

namespace dn::protocol {
namespace {

using wire::Field;

constexpr uint32_t kDefinedCapabilities = 0;  // HELLO.capabilities bits known to protocol 1.1 (none)
using wire::Reader;

bool read_format(Reader& r, Format& out, const Field& f) {
  uint8_t v;
  if (!r.u8(v, f)) return false;
  if (v != static_cast<uint8_t>(Format::F16) && v != static_cast<uint8_t>(Format::F32))
    return r.fail(ErrorCode::Malformed, f, f.str() + " is " + std::to_string(v) + "; must be 1 (F16) or 2 (F32)");
  out = static_cast<Format>(v);
  return true;
}

bool read_channel_id(Reader& r, ChannelId& out, const Field& f) {
  uint8_t v;
  if (!r.u8(v, f)) return false;
  if (!find_channel(static_cast<ChannelId>(v)))
    return r.fail(ErrorCode::Malformed, f, f.str() + " is " + std::to_string(v) + ", which is not a known channel id");
  out = static_cast<ChannelId>(v);
  return true;
}

bool read_bool(Reader& r, bool& out, const Field& f) {
  uint8_t v;
  if (!r.u8(v, f)) return false;
  if (v > 1) return r.fail(ErrorCode::Malformed, f, f.str() + " is " + std::to_string(v) + "; must be 0 or 1");
  out = v == 1;
  return true;
}

bool read_dimension(Reader& r, uint32_t& out, const Field& f) {
  if (!r.u32(out, f)) return false;
  if (out == 0) return r.fail(ErrorCode::Malformed, f, f.str() + " must be at least 1, found 0");
  return true;
}

// Channel declarations of OPEN_SESSION and SESSION: known ids other than
// Output, each at most once.
bool read_channel_decls(Reader& r, std::vector<ChannelDecl>& out, std::string_view type, std::string_view base) {
  uint16_t n;
  if (!r.count(n, Field{type, base}, wire::kMaxChannels, 2)) return false;
  out.clear();
  out.reserve(n);
  uint64_t seen = 0;
  for (uint16_t i = 0; i < n; ++i) {
    ChannelDecl c;
    const Field id_field{type, base, i, ".id"};
    if (!read_channel_id(r, c.id, id_field)) return false;
    if (c.id == ChannelId::Output)
      return r.fail(ErrorCode::Malformed, id_field,
                    id_field.str() + " is 32 (output), which is not an input channel");
    if (seen & channel_bit(c.id))
      return r.fail(ErrorCode::Malformed, id_field,
                    id_field.str() + " declares channel " + std::string(find_channel(c.id)->name) + " a second time");
    seen |= channel_bit(c.id);
    if (!read_format(r, c.format, Field{type, base, i, ".format"})) return false;
    out.push_back(c);
  }
  return true;
}

// Plane list of FRAME and RESULT: views into the payload, no copy.
bool read_planes(Reader& r, std::vector<PlaneView>& out, std::string_view type, std::string_view base) {
  uint16_t n;
  if (!r.count(n, Field{type, base}, wire::kMaxPlanes, wire::kPlaneHeaderBytes)) return false;
  out.clear();
  out.reserve(n);
  uint64_t seen = 0;
  for (uint16_t i = 0; i < n; ++i) {
    PlaneView p;
    const Field id_field{type, base, i, ".id"};
    if (!read_channel_id(r, p.id, id_field)) return false;
    if (seen & channel_bit(p.id))
      return r.fail(ErrorCode::Malformed, id_field,
                    id_field.str() + " carries channel " + std::string(find_channel(p.id)->name) + " a second time");
    seen |= channel_bit(p.id);
    if (!read_format(r, p.format, Field{type, base, i, ".format"})) return false;
    if (!r.zero_bytes(2, Field{type, base, i, ".reserved"})) return false;
    uint64_t len;
    if (!r.u64(len, Field{type, base, i, ".byte_length"})) return false;
    if (len > r.remaining())
      return r.fail(ErrorCode::Malformed, Field{type, base, i, ".byte_length"},
                    Field{type, base, i, ".byte_length"}.str() + " is " + std::to_string(len) + " but only " +
                        std::to_string(r.remaining()) + " bytes remain");
    if (!r.bytes(p.bytes, len, Field{type, base, i, ".bytes"})) return false;
    out.push_back(p);
  }
  return true;
}

bool read_mat(Reader& r, Mat4& m, std::string_view type, std::string_view base) {
  for (size_t i = 0; i < m.size(); ++i)
    if (!r.f32(m[i], Field{type, base, static_cast<long>(i)})) return false;
  return true;
}

// Named f64 values (OPEN_SESSION.parameters, RESULT.timings, STATS.values).
template <class T, class Value>
bool read_named_values(Reader& r, std::vector<T>& out, std::string_view type, std::string_view base, size_t max_count,
                       Value T::*value, std::string_view value_name, bool unique_names) {
  uint16_t n;
  if (!r.count(n, Field{type, base}, max_count, 2 + 8)) return false;
  out.clear();
  out.reserve(n);
  for (uint16_t i = 0; i < n; ++i) {
    T t;
    const Field name_field{type, base, i, ".name"};
    if (!r.str(t.name, name_field, wire::kMaxNameBytes)) return false;
    if (unique_names)
      for (const auto& prev : out)
        if (prev.name == t.name)
          return r.fail(ErrorCode::Malformed, name_field,
                        name_field.str() + " \"" + t.name + "\" appears a second time");
    if (!r.f64(t.*value, Field{type, base, i, value_name})) return false;
    out.push_back(std::move(t));
  }
  return true;
}

struct Ctx {
  Reader& r;
  const Header& h;
  std::string_view type;
  Field f(std::string_view name, long index = -1, std::string_view sub = {}) const {
    return Field{type, name, index, sub};
  }
  bool newer_minor() const { return h.version_minor > kVersionMinor; }
  // A field appended by minor n is on the wire when the sender's minor is >= n
  // (a sender writes only what both sides know, docs/protocol.md §10).
  bool has(uint8_t minor) const { return h.version_minor >= minor; }
};

// SESSION.watch_key and ATTACH.watch_key (1.6): empty or 32 lowercase hex digits.
bool read_watch_key(Ctx& c, std::optional<std::string>& out) {
  if (!c.has(kWatchKeyMinor)) {
    out.reset();
    return true;
  }
  const Field f = c.f("watch_key");
  std::string key;
  if (!c.r.str(key, f, kWatchKeyLength)) return false;
  // The message does not repeat the key: a near miss of a real one would end up in logs.
  if (!is_well_formed_watch_key(key)) {
    std::string found = std::to_string(key.size()) + " bytes";
    if (key.size() == kWatchKeyLength)
      found = "byte " + std::to_string(key.find_first_not_of("0123456789abcdef")) + " is not one";
    return c.r.fail(ErrorCode::Malformed, f,
                    f.str() + " must be empty or " + std::to_string(kWatchKeyLength) +
                        " lowercase hex digits (0-9, a-f); " + found);
  }
  out = std::move(key);
  return true;
}

// A string field appended by minor `since` (unset when the message is older):
// printable ASCII, possibly empty; spaces only where `spaces` allows them.
bool read_appended_text(Ctx& c, uint8_t since, const char* name, size_t max_bytes, bool spaces,
                        std::optional<std::string>& out) {
  if (!c.has(since)) {
    out.reset();
    return true;
  }
  const Field f = c.f(name);
  std::string text;
  if (!c.r.str(text, f, max_bytes)) return false;
  const char lowest = spaces ? 0x20 : 0x21;
  for (size_t i = 0; i < text.size(); ++i)
    if (text[i] < lowest || text[i] > 0x7e)
      return c.r.fail(ErrorCode::Malformed, f,
                      f.str() + (spaces ? " must be printable ASCII" : " must be printable ASCII without spaces") +
                          "; byte " + std::to_string(i) + " is not");
  out = std::move(text);
  return true;
}

bool decode(Ctx& c, Hello& m) {
  Reader& r = c.r;
  const Field cap = c.f("capabilities");
  if (!r.u32(m.capabilities, cap)) return false;
  // Capability bits are defined by later minor versions; 1.0 and 1.1 define
  // none. Bits from a newer minor are not understood here and are dropped, so
  // the decoded message is always valid at this version.
  if (m.capabilities & ~kDefinedCapabilities) {
    if (!c.newer_minor())
      return r.fail(ErrorCode::ReservedFlags, cap,
                    cap.str() + " is " + std::to_string(m.capabilities) + "; no capability is defined in protocol 1.1");
    m.capabilities &= kDefinedCapabilities;
  }
  return r.str(m.client_name, c.f("client_name"), wire::kMaxNameBytes) &&
         r.str(m.auth_token, c.f("auth_token"), wire::kMaxTokenBytes);
}

// One pipeline's parameter table (WELCOME 1.1): unique names, min <= default <= max.
bool read_parameter_infos(Reader& r, std::vector<ParameterInfo>& out, std::string_view type, long pipeline) {
  const std::string base = "pipeline_parameters[" + std::to_string(pipeline) + "]";
  uint16_t n;
  if (!r.count(n, Field{type, base}, wire::kMaxParameters, wire::kParameterInfoMinBytes)) return false;
  out.clear();
  out.reserve(n);
  for (uint16_t i = 0; i < n; ++i) {
    ParameterInfo q;
    const Field name_field{type, base, i, ".name"};
    const Field default_field{type, base, i, ".default_value"};
    const Field max_field{type, base, i, ".max_value"};
    if (!r.str(q.name, name_field, wire::kMaxNameBytes)) return false;
    for (const auto& prev : out)
      if (prev.name == q.name)
        return r.fail(ErrorCode::Malformed, name_field, name_field.str() + " \"" + q.name + "\" appears a second time");
    if (!r.f64(q.default_value, default_field) || !r.f64(q.min_value, Field{type, base, i, ".min_value"}) ||
        !r.f64(q.max_value, max_field))
      return false;
    if (q.max_value < q.min_value)
      return r.fail(ErrorCode::Malformed, max_field,
                    max_field.str() + " " + std::to_string(q.max_value) + " is below min_value " +
                        std::to_string(q.min_value));
    if (q.default_value < q.min_value || q.default_value > q.max_value)
      return r.fail(ErrorCode::Malformed, default_field,
                    default_field.str() + " " + std::to_string(q.default_value) + " is outside [" +
                        std::to_string(q.min_value) + ", " + std::to_string(q.max_value) + "]");
    if (!read_bool(r, q.integer, Field{type, base, i, ".integer"}) ||
        !r.str(q.description, Field{type, base, i, ".description"}, wire::kMaxDescriptionBytes))
      return false;
    out.push_back(std::move(q));
  }
  return true;
}

bool decode(Ctx& c, Welcome& m) {
  Reader& r = c.r;
  if (!r.str(m.server_version, c.f("server_version"), wire::kMaxVersionBytes) ||
      !r.str(m.device_name, c.f("device_name"), wire::kMaxVersionBytes) ||
      !r.u64(m.limits.max_message_bytes, c.f("limits.max_message_bytes")) ||
      !r.u64(m.limits.max_session_bytes, c.f("limits.max_session_bytes")) ||
      !r.u32(m.limits.max_sessions, c.f("limits.max_sessions")) ||
      !r.u32(m.limits.max_width, c.f("limits.max_width")) ||
      !r.u32(m.limits.max_height, c.f("limits.max_height")) ||
      !r.u32(m.limits.max_frames_in_flight, c.f("limits.max_frames_in_flight")))
    return false;
  const std::string_view type = c.type, base = "pipelines";
  uint16_t n;
  if (!r.count(n, Field{type, base}, wire::kMaxPipelines, 2 + 8 + 8)) return false;
  m.pipelines.clear();
  m.pipelines.reserve(n);
  for (uint16_t i = 0; i < n; ++i) {
    PipelineInfo p;
    if (!r.str(p.name, Field{type, base, i, ".name"}, wire::kMaxNameBytes) ||
        !r.u64(p.required_channels, Field{type, base, i, ".required_channels"}) ||
        !r.u64(p.optional_channels, Field{type, base, i, ".optional_channels"}))
      return false;
    m.pipelines.push_back(std::move(p));
  }
  // 1.1 appends the parameter tables. A 1.1 server omits them only for a 1.0
  // client, which would skip them anyway, so a 1.1 header means they are here.
  m.has_parameters = c.h.version_minor >= 1;
  if (!m.has_parameters) return true;
  const Field tables{type, "pipeline_parameters"};
  uint16_t tn;
  if (!r.count(tn, tables, wire::kMaxPipelines, 2)) return false;
  if (tn != n)
    return r.fail(ErrorCode::Malformed, tables,
                  tables.str() + " count " + std::to_string(tn) + " differs from the " + std::to_string(n) +
                      " pipelines");
  for (uint16_t i = 0; i < n; ++i)
    if (!read_parameter_infos(r, m.pipelines[i].parameters, type, i)) return false;
  return true;
}

bool decode(Ctx& c, Error& m) {
  Reader& r = c.r;
  uint32_t code;
  const Field code_field = c.f("code");
  if (!r.u32(code, code_field)) return false;
  if (!wire::is_known_error_code(code))
    return r.fail(ErrorCode::Malformed, code_field,
                  code_field.str() + " is " + std::to_string(code) + ", which is not a known error code");
  m.code = static_cast<ErrorCode>(code);
  return r.str(m.field, c.f("field"), wire::kMaxTextBytes) &&
         r.str(m.message, c.f("message"), wire::kMaxTextBytes);
}

bool decode(Ctx& c, OpenSession& m) {
  Reader& r = c.r;
  return read_dimension(r, m.width, c.f("width")) && read_dimension(r, m.height, c.f("height")) &&
         r.str(m.pipeline, c.f("pipeline"), wire::kMaxNameBytes) &&
         read_format(r, m.output_format, c.f("output_format")) &&
         r.zero_bytes(1, c.f("reserved")) &&
         read_named_values(r, m.parameters, c.type, "parameters", wire::kMaxParameters, &Parameter::value, ".value",
                           true) &&
         read_channel_decls(r, m.channels, c.type, "channels");
}

bool decode(Ctx& c, Session& m) {
  Reader& r = c.r;
  if (!r.u64(m.session_id, c.f("session_id")) || !read_dimension(r, m.width, c.f("width")) ||
      !read_dimension(r, m.height, c.f("height")) ||
      !r.str(m.pipeline, c.f("pipeline"), wire::kMaxNameBytes) ||
      !read_format(r, m.output_format, c.f("output_format")))
    return false;
  if (!read_bool(r, m.read_only, c.f("read_only"))) return false;
  return r.u64(m.device_bytes, c.f("device_bytes")) && read_channel_decls(r, m.channels, c.type, "channels") &&
         read_watch_key(c, m.watch_key) &&
         read_appended_text(c, kWatchUrlMinor, "watch_url", kMaxWatchUrlBytes, false, m.watch_url) &&  // 1.8
         read_appended_text(c, kAutoMinor, "pipeline_reason", kMaxPipelineReasonBytes, true,  // 1.10
                            m.pipeline_reason);
}

bool decode(Ctx& c, Frame& m) {
  Reader& r = c.r;
  FrameInfo& f = m.info;
  const Field flags_field = c.f("flags");
  if (!r.u64(f.session_id, c.f("session_id")) || !r.u64(f.frame_index, c.f("frame_index")) ||
      !r.u32(f.flags, flags_field))
    return false;
  if (f.flags & ~kDefinedFrameFlags)
    return r.fail(ErrorCode::ReservedFlags, flags_field,
                  flags_field.str() + " has reserved bits set: " + std::to_string(f.flags & ~kDefinedFrameFlags));
  uint8_t motion;
  const Field motion_field = c.f("motion");
  if (!r.u8(motion, motion_field)) return false;
  if (motion > static_cast<uint8_t>(MotionConvention::UvToPrevious))
    return r.fail(ErrorCode::Malformed, motion_field,
                  motion_field.str() + " is " + std::to_string(motion) + "; must be 0, 1 or 2");
  f.motion = static_cast<MotionConvention>(motion);
  if (!r.zero_bytes(3, c.f("reserved")) || !read_mat(r, f.view, c.type, "view") ||
      !read_mat(r, f.projection, c.type, "projection") || !read_mat(r, f.prev_view, c.type, "prev_view") ||
      !read_mat(r, f.prev_projection, c.type, "prev_projection"))
    return false;
  for (long i = 0; i < 2; ++i)
    if (!r.f32(f.jitter[i], c.f("jitter", i))) return false;
  for (long i = 0; i < 2; ++i)
    if (!r.f32(f.prev_jitter[i], c.f("prev_jitter", i))) return false;
  return read_planes(r, m.planes, c.type, "planes");
}

// RESULT.samples (1.9): counted 0 or 1; min <= median, both 0 when not counted.
bool read_samples(Ctx& c, std::optional<SampleCounts>& out) {
  out.reset();
  if (!c.has(kSamplesMinor)) return true;
  SampleCounts n;
  const Field min = c.f("samples.min");
  if (!read_bool(c.r, n.counted, c.f("samples.counted")) || !c.r.u32(n.min, min) ||
      !c.r.u32(n.median, c.f("samples.median")))
    return false;
  if (!n.counted && (n.min != 0 || n.median != 0))
    return c.r.fail(ErrorCode::Malformed, min, min.str() + " and .median must be 0 when samples.counted is 0");
  if (n.min > n.median)
    return c.r.fail(ErrorCode::Malformed, min,
                    min.str() + " " + std::to_string(n.min) + " is above the median " + std::to_string(n.median));
  out = n;
  return true;
}

bool decode(Ctx& c, Result& m) {
  Reader& r = c.r;
  return r.u64(m.session_id, c.f("session_id")) && r.u64(m.frame_index, c.f("frame_index")) &&
         read_named_values(r, m.timings, c.type, "timings", wire::kMaxTimings, &PassTiming::milliseconds,
                           ".milliseconds", false) &&
         read_planes(r, m.planes, c.type, "planes") && read_samples(c, m.samples);
}

bool decode(Ctx& c, Attach& m) {
  return c.r.u64(m.session_id, c.f("session_id")) && read_watch_key(c, m.watch_key);
}
bool decode(Ctx& c, Ping& m) { return c.r.u64(m.payload, c.f("payload")); }
bool decode(Ctx& c, Pong& m) { return c.r.u64(m.payload, c.f("payload")); }
bool decode(Ctx& c, CloseSession& m) { return c.r.u64(m.session_id, c.f("session_id")); }
bool decode(Ctx& c, SessionClosed& m) {
  return c.r.u64(m.session_id, c.f("session_id")) &&
         c.r.u64(m.frames_processed, c.f("frames_processed"));
}
bool decode(Ctx&, StatsRequest&) { return true; }
bool decode(Ctx& c, Stats& m) {
  return read_named_values(c.r, m.values, c.type, "values", wire::kMaxStats, &StatValue::value, ".value", false);
}

template <class T>
std::optional<DecodeError> run(const Header& header, std::span<const uint8_t> payload, Message& out) {
  const std::string_view type = to_string(header.type);
  Reader r(payload, type);
  Ctx c{r, header, type};
  T m{};
  // A message from a newer minor version may carry fields appended after the
  // ones this version knows; they are skipped (docs/protocol.md, "Versioning").
  if (!decode(c, m) || !r.finish(c.newer_minor())) return std::move(*r.error());
  out = std::move(m);
  return std::nullopt;
}

}  // namespace

std::optional<DecodeError> decode_payload(const Header& header, std::span<const uint8_t> payload, Message& out) {
  if (payload.size() != header.payload_length)
    return DecodeError{ErrorCode::Malformed, "header.payload_length",
                       "payload_length " + std::to_string(header.payload_length) + " but " +
                           std::to_string(payload.size()) + " payload bytes were given"};
  switch (header.type) {
    case MessageType::Hello: return run<Hello>(header, payload, out);
    case MessageType::Welcome: return run<Welcome>(header, payload, out);
    case MessageType::Error: return run<Error>(header, payload, out);
    case MessageType::OpenSession: return run<OpenSession>(header, payload, out);
    case MessageType::Session: return run<Session>(header, payload, out);
    case MessageType::Frame: return run<Frame>(header, payload, out);
    case MessageType::Result: return run<Result>(header, payload, out);
    case MessageType::Attach: return run<Attach>(header, payload, out);
    case MessageType::Ping: return run<Ping>(header, payload, out);
    case MessageType::Pong: return run<Pong>(header, payload, out);
    case MessageType::CloseSession: return run<CloseSession>(header, payload, out);
    case MessageType::SessionClosed: return run<SessionClosed>(header, payload, out);
    case MessageType::StatsRequest: return run<StatsRequest>(header, payload, out);
    case MessageType::Stats: return run<Stats>(header, payload, out);
  }
  return DecodeError{ErrorCode::UnknownMessageType, "header.type",
                     "message type " + std::to_string(static_cast<uint16_t>(header.type)) + " is not known"};
}

}  // namespace dn::protocol
