#include "support.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <sstream>

namespace dn::protocol::test {
namespace {

template <class T>
T uniform(std::mt19937& rng, T lo, T hi) {
  return std::uniform_int_distribution<T>(lo, hi)(rng);
}

uint64_t random_u64(std::mt19937& rng) {
  switch (uniform<int>(rng, 0, 3)) {
    case 0: return 0;
    case 1: return ~uint64_t{0};
    case 2: return uniform<uint64_t>(rng, 0, 1000);
    default: return (static_cast<uint64_t>(rng()) << 32) | rng();
  }
}
uint32_t random_u32(std::mt19937& rng) {
  switch (uniform<int>(rng, 0, 3)) {
    case 0: return 0;
    case 1: return ~uint32_t{0};
    case 2: return uniform<uint32_t>(rng, 0, 1000);
    default: return rng();
  }
}

// Any finite float, including -0, subnormals and extremes.
float random_float(std::mt19937& rng) {
  switch (uniform<int>(rng, 0, 4)) {
    case 0: return std::uniform_real_distribution<float>(-10.f, 10.f)(rng);
    case 1: return uniform<int>(rng, 0, 1) ? -0.0f : 0.0f;
    case 2: return std::bit_cast<float>(static_cast<uint32_t>(rng()) & 0x807FFFFFu);  // subnormal (or zero)
    default:
      for (;;) {
        float f = std::bit_cast<float>(static_cast<uint32_t>(rng()));
        if (std::isfinite(f)) return f;
      }
  }
}
double random_double(std::mt19937& rng) {
  switch (uniform<int>(rng, 0, 3)) {
    case 0: return std::uniform_real_distribution<double>(-1e3, 1e3)(rng);
    case 1: return uniform<int>(rng, 0, 1) ? -0.0 : 0.0;
    default:
      for (;;) {
        double d = std::bit_cast<double>(random_u64(rng) ^ (static_cast<uint64_t>(rng()) << 32));
        if (std::isfinite(d)) return d;
      }
  }
}

// Empty, or 32 lowercase hex digits: the two shapes a 1.6 watch key takes.
std::string random_watch_key(std::mt19937& rng) {
  if (uniform<int>(rng, 0, 3) == 0) return {};
  std::string key;
  for (size_t i = 0; i < kWatchKeyLength; ++i) key += "0123456789abcdef"[uniform<int>(rng, 0, 15)];
  return key;
}

// Valid UTF-8 without NUL, at most max_bytes long.
std::string random_string(std::mt19937& rng, size_t max_bytes) {
  static const char* pieces[] = {"a", "Z", "0", " ", "-", "_", ".", "\x7f", "\xc3\xa9" /* é */,
                                 "\xe2\x82\xac" /* € */, "\xf0\x9f\x98\x80" /* 😀 */};
  size_t target = uniform<int>(rng, 0, 3) == 0 ? max_bytes : uniform<size_t>(rng, 0, std::min<size_t>(max_bytes, 24));
  std::string s;
  for (int tries = 0; tries < 4 * static_cast<int>(target) + 4 && s.size() < target; ++tries) {
    std::string_view p = pieces[uniform<size_t>(rng, 0, std::size(pieces) - 1)];
    if (s.size() + p.size() <= target) s += p;
  }
  return s;
}

Format random_format(std::mt19937& rng) { return uniform<int>(rng, 0, 1) ? Format::F16 : Format::F32; }

// Distinct channel ids drawn from kChannels (optionally without Output).
std::vector<ChannelId> random_channel_set(std::mt19937& rng, bool allow_output) {
  std::vector<ChannelId> ids;
  for (const auto& c : kChannels)
    if (allow_output || c.id != ChannelId::Output) ids.push_back(c.id);
  std::shuffle(ids.begin(), ids.end(), rng);
  ids.resize(uniform<size_t>(rng, 0, ids.size()));
  return ids;
}

std::vector<ChannelDecl> random_channels(std::mt19937& rng) {
  std::vector<ChannelDecl> out;
  for (ChannelId id : random_channel_set(rng, false)) out.push_back({id, random_format(rng)});
  return out;
}

std::vector<PlaneView> random_planes(std::mt19937& rng, OwnedMessage& owner, size_t max_plane_bytes) {
  std::vector<PlaneView> out;
  for (ChannelId id : random_channel_set(rng, true)) {
    auto buf = std::make_shared<std::vector<uint8_t>>(uniform<size_t>(rng, 0, max_plane_bytes));
    for (auto& b : *buf) b = static_cast<uint8_t>(rng());
    out.push_back({id, random_format(rng), std::span<const uint8_t>(*buf)});
    owner.storage.push_back(std::move(buf));
  }
  return out;
}

std::vector<std::string> unique_names(std::mt19937& rng, size_t n) {
  std::vector<std::string> names;
  while (names.size() < n) {
    std::string s = random_string(rng, 64);
    if (std::find(names.begin(), names.end(), s) == names.end()) names.push_back(std::move(s));
  }
  return names;
}

Mat4 random_mat(std::mt19937& rng) {
  Mat4 m;
  for (float& v : m) v = random_float(rng);
  return m;
}

}  // namespace

uint32_t random_flags(MessageType type, std::mt19937& rng) {
  return type == MessageType::Frame && uniform<int>(rng, 0, 1) ? kFlagNoOutput : 0u;
}

OwnedMessage random_message(MessageType type, std::mt19937& rng, size_t max_plane_bytes) {
  OwnedMessage o;
  // Lists are usually short, sometimes at their documented maximum.
  auto list_size = [&](size_t max) { return uniform<int>(rng, 0, 9) == 0 ? max : uniform<size_t>(rng, 0, 4); };
  switch (type) {
    case MessageType::Hello: {
      Hello m;
      m.capabilities = 0;
      m.client_name = random_string(rng, 64);
      m.auth_token = random_string(rng, 256);
      o.message = m;
      break;
    }
    case MessageType::Welcome: {
      Welcome m;
      m.server_version = random_string(rng, 256);
      m.device_name = random_string(rng, 256);
      m.limits = {random_u64(rng), random_u64(rng), random_u32(rng), random_u32(rng), random_u32(rng), random_u32(rng)};
      size_t n = list_size(64);
      for (size_t i = 0; i < n; ++i) m.pipelines.push_back({random_string(rng, 64), random_u64(rng), random_u64(rng)});
      // The current minor's full message: parameter tables (1.1), kept within
      // the 65536-byte WELCOME limit that the list limits alone could exceed.
      m.has_parameters = true;
      size_t bytes = 2 + 256 + 2 + 256 + 32 + 2 + n * (2 + 64 + 16) + 2 + n * 2;
      for (auto& p : m.pipelines) {
        for (auto& name : unique_names(rng, list_size(64))) {
          std::array<double, 3> v{random_double(rng), random_double(rng), random_double(rng)};
          std::sort(v.begin(), v.end());
          ParameterInfo q{name, v[1], v[0], v[2], uniform<int>(rng, 0, 1) == 1, random_string(rng, 512)};
          bytes += 2 + q.name.size() + 25 + 2 + q.description.size();
          if (bytes > 65536) break;
          p.parameters.push_back(std::move(q));
        }
      }
      o.message = m;
      break;
    }
    case MessageType::Error: {
      Error m;
      m.code = static_cast<ErrorCode>(uniform<uint32_t>(rng, 1, 19));
      m.field = random_string(rng, 1024);
      m.message = random_string(rng, 1024);
      o.message = m;
      break;
    }
    case MessageType::OpenSession: {
      OpenSession m;
      m.width = std::max<uint32_t>(1, random_u32(rng));
      m.height = std::max<uint32_t>(1, random_u32(rng));
      m.pipeline = random_string(rng, 64);
      m.output_format = random_format(rng);
      for (auto& name : unique_names(rng, list_size(64))) m.parameters.push_back({name, random_double(rng)});
      m.channels = random_channels(rng);
      o.message = m;
      break;
    }
    case MessageType::Session: {
      Session m;
      m.session_id = random_u64(rng);
      m.width = std::max<uint32_t>(1, random_u32(rng));
      m.height = std::max<uint32_t>(1, random_u32(rng));
      m.pipeline = random_string(rng, 64);
      m.output_format = random_format(rng);
      m.device_bytes = random_u64(rng);
      m.read_only = uniform<int>(rng, 0, 1) == 1;
      m.channels = random_channels(rng);
      m.watch_key = random_watch_key(rng);
      m.watch_url = uniform<int>(rng, 0, 1) ? "" : "tcp://lb-" + std::to_string(random_u32(rng)) + ":7101";
      m.pipeline_reason = uniform<int>(rng, 0, 1) ? "" : "the full G-buffer " + std::to_string(random_u32(rng));
      o.message = m;
      break;
    }
    case MessageType::Frame: {
      Frame m;
      m.info.session_id = random_u64(rng);
      m.info.frame_index = random_u64(rng);
      m.info.flags = uniform<int>(rng, 0, 1) ? kFrameReset : 0u;
      m.info.motion = static_cast<MotionConvention>(uniform<int>(rng, 0, 2));
      m.info.view = random_mat(rng);
      m.info.projection = random_mat(rng);
      m.info.prev_view = random_mat(rng);
      m.info.prev_projection = random_mat(rng);
      m.info.jitter = {random_float(rng), random_float(rng)};
      m.info.prev_jitter = {random_float(rng), random_float(rng)};
      m.planes = random_planes(rng, o, max_plane_bytes);
      o.message = m;
      break;
    }
    case MessageType::Result: {
      Result m;
      m.session_id = random_u64(rng);
      m.frame_index = random_u64(rng);
      size_t n = list_size(64);
      for (size_t i = 0; i < n; ++i) m.timings.push_back({random_string(rng, 64), random_double(rng)});
      m.planes = random_planes(rng, o, max_plane_bytes);
      // Always on the wire from this version's sender (1.9), as SESSION's watch key and URL.
      const uint32_t a = random_u32(rng), b = random_u32(rng);
      m.samples = uniform<int>(rng, 0, 3) ? SampleCounts{true, std::min(a, b), std::max(a, b)} : SampleCounts{};
      o.message = m;
      break;
    }
    case MessageType::Attach: o.message = Attach{random_u64(rng), random_watch_key(rng)}; break;
    case MessageType::Ping: o.message = Ping{random_u64(rng)}; break;
    case MessageType::Pong: o.message = Pong{random_u64(rng)}; break;
    case MessageType::CloseSession: o.message = CloseSession{random_u64(rng)}; break;
    case MessageType::SessionClosed: o.message = SessionClosed{random_u64(rng), random_u64(rng)}; break;
    case MessageType::StatsRequest: o.message = StatsRequest{}; break;
    case MessageType::Stats: {
      Stats m;
      size_t n = list_size(256);
      for (size_t i = 0; i < n; ++i) m.values.push_back({random_string(rng, 64), random_double(rng)});
      o.message = m;
      break;
    }
  }
  return o;
}

// ---- comparison --------------------------------------------------------------
namespace {

struct Differ {
  std::ostringstream out;
  bool done = false;

  template <class T>
  void eq(const char* what, const T& a, const T& b) {
    if (done || a == b) return;
    done = true;
    out << what << " differs";
  }
  void bits(const char* what, float a, float b) {
    if (done || std::bit_cast<uint32_t>(a) == std::bit_cast<uint32_t>(b)) return;
    done = true;
    out << what << " differs: " << a << " vs " << b;
  }
  void bits(const char* what, double a, double b) {
    if (done || std::bit_cast<uint64_t>(a) == std::bit_cast<uint64_t>(b)) return;
    done = true;
    out << what << " differs: " << a << " vs " << b;
  }
  void channels(const std::vector<ChannelDecl>& a, const std::vector<ChannelDecl>& b) {
    eq("channels.size", a.size(), b.size());
    for (size_t i = 0; i < a.size() && !done; ++i) {
      eq("channels[].id", a[i].id, b[i].id);
      eq("channels[].format", a[i].format, b[i].format);
    }
  }
  void planes(const std::vector<PlaneView>& a, const std::vector<PlaneView>& b) {
    eq("planes.size", a.size(), b.size());
    for (size_t i = 0; i < a.size() && !done; ++i) {
      eq("planes[].id", a[i].id, b[i].id);
      eq("planes[].format", a[i].format, b[i].format);
      eq("planes[].bytes.size", a[i].bytes.size(), b[i].bytes.size());
      if (!done && !std::equal(a[i].bytes.begin(), a[i].bytes.end(), b[i].bytes.begin())) {
        done = true;
        out << "planes[" << i << "].bytes content differs";
      }
    }
  }
  void mat(const char* what, const Mat4& a, const Mat4& b) {
    for (size_t i = 0; i < 16; ++i) bits(what, a[i], b[i]);
  }

  void operator()(const Hello& a, const Hello& b) {
    eq("capabilities", a.capabilities, b.capabilities);
    eq("client_name", a.client_name, b.client_name);
    eq("auth_token", a.auth_token, b.auth_token);
  }
  void operator()(const Welcome& a, const Welcome& b) {
    eq("server_version", a.server_version, b.server_version);
    eq("device_name", a.device_name, b.device_name);
    eq("limits.max_message_bytes", a.limits.max_message_bytes, b.limits.max_message_bytes);
    eq("limits.max_session_bytes", a.limits.max_session_bytes, b.limits.max_session_bytes);
    eq("limits.max_sessions", a.limits.max_sessions, b.limits.max_sessions);
    eq("limits.max_width", a.limits.max_width, b.limits.max_width);
    eq("limits.max_height", a.limits.max_height, b.limits.max_height);
    eq("limits.max_frames_in_flight", a.limits.max_frames_in_flight, b.limits.max_frames_in_flight);
    eq("pipelines.size", a.pipelines.size(), b.pipelines.size());
    for (size_t i = 0; i < a.pipelines.size() && !done; ++i) {
      eq("pipelines[].name", a.pipelines[i].name, b.pipelines[i].name);
      eq("pipelines[].required_channels", a.pipelines[i].required_channels, b.pipelines[i].required_channels);
      eq("pipelines[].optional_channels", a.pipelines[i].optional_channels, b.pipelines[i].optional_channels);
      eq("pipelines[].parameters.size", a.pipelines[i].parameters.size(), b.pipelines[i].parameters.size());
      for (size_t j = 0; j < a.pipelines[i].parameters.size() && !done; ++j) {
        const ParameterInfo &x = a.pipelines[i].parameters[j], &y = b.pipelines[i].parameters[j];
        eq("pipelines[].parameters[].name", x.name, y.name);
        bits("pipelines[].parameters[].default_value", x.default_value, y.default_value);
        bits("pipelines[].parameters[].min_value", x.min_value, y.min_value);
        bits("pipelines[].parameters[].max_value", x.max_value, y.max_value);
        eq("pipelines[].parameters[].integer", x.integer, y.integer);
        eq("pipelines[].parameters[].description", x.description, y.description);
      }
    }
    eq("has_parameters", a.has_parameters, b.has_parameters);
  }
  void operator()(const Error& a, const Error& b) {
    eq("code", a.code, b.code);
    eq("field", a.field, b.field);
    eq("message", a.message, b.message);
  }
  void operator()(const OpenSession& a, const OpenSession& b) {
    eq("width", a.width, b.width);
    eq("height", a.height, b.height);
    eq("pipeline", a.pipeline, b.pipeline);
    eq("output_format", a.output_format, b.output_format);
    eq("parameters.size", a.parameters.size(), b.parameters.size());
    for (size_t i = 0; i < a.parameters.size() && !done; ++i) {
      eq("parameters[].name", a.parameters[i].name, b.parameters[i].name);
      bits("parameters[].value", a.parameters[i].value, b.parameters[i].value);
    }
    channels(a.channels, b.channels);
  }
  void operator()(const Session& a, const Session& b) {
    eq("session_id", a.session_id, b.session_id);
    eq("width", a.width, b.width);
    eq("height", a.height, b.height);
    eq("pipeline", a.pipeline, b.pipeline);
    eq("output_format", a.output_format, b.output_format);
    eq("device_bytes", a.device_bytes, b.device_bytes);
    eq("read_only", a.read_only, b.read_only);
    channels(a.channels, b.channels);
    eq("watch_key", a.watch_key, b.watch_key);
    eq("watch_url", a.watch_url, b.watch_url);
    eq("pipeline_reason", a.pipeline_reason, b.pipeline_reason);
  }
  void operator()(const Frame& a, const Frame& b) {
    eq("session_id", a.info.session_id, b.info.session_id);
    eq("frame_index", a.info.frame_index, b.info.frame_index);
    eq("flags", a.info.flags, b.info.flags);
    eq("motion", a.info.motion, b.info.motion);
    mat("view", a.info.view, b.info.view);
    mat("projection", a.info.projection, b.info.projection);
    mat("prev_view", a.info.prev_view, b.info.prev_view);
    mat("prev_projection", a.info.prev_projection, b.info.prev_projection);
    for (size_t i = 0; i < 2; ++i) {
      bits("jitter", a.info.jitter[i], b.info.jitter[i]);
      bits("prev_jitter", a.info.prev_jitter[i], b.info.prev_jitter[i]);
    }
    planes(a.planes, b.planes);
  }
  void operator()(const Result& a, const Result& b) {
    eq("session_id", a.session_id, b.session_id);
    eq("frame_index", a.frame_index, b.frame_index);
    eq("timings.size", a.timings.size(), b.timings.size());
    for (size_t i = 0; i < a.timings.size() && !done; ++i) {
      eq("timings[].name", a.timings[i].name, b.timings[i].name);
      bits("timings[].milliseconds", a.timings[i].milliseconds, b.timings[i].milliseconds);
    }
    planes(a.planes, b.planes);
    eq("samples.present", a.samples.has_value(), b.samples.has_value());
    if (a.samples && b.samples) {
      eq("samples.counted", a.samples->counted, b.samples->counted);
      eq("samples.min", a.samples->min, b.samples->min);
      eq("samples.median", a.samples->median, b.samples->median);
    }
  }
  void operator()(const Attach& a, const Attach& b) {
    eq("session_id", a.session_id, b.session_id);
    eq("watch_key", a.watch_key, b.watch_key);
  }
  void operator()(const Ping& a, const Ping& b) { eq("payload", a.payload, b.payload); }
  void operator()(const Pong& a, const Pong& b) { eq("payload", a.payload, b.payload); }
  void operator()(const CloseSession& a, const CloseSession& b) { eq("session_id", a.session_id, b.session_id); }
  void operator()(const SessionClosed& a, const SessionClosed& b) {
    eq("session_id", a.session_id, b.session_id);
    eq("frames_processed", a.frames_processed, b.frames_processed);
  }
  void operator()(const StatsRequest&, const StatsRequest&) {}
  void operator()(const Stats& a, const Stats& b) {
    eq("values.size", a.values.size(), b.values.size());
    for (size_t i = 0; i < a.values.size() && !done; ++i) {
      eq("values[].name", a.values[i].name, b.values[i].name);
      bits("values[].value", a.values[i].value, b.values[i].value);
    }
  }
  template <class A, class B>
  void operator()(const A&, const B&) {
    done = true;
    out << "message types differ";
  }
};

}  // namespace

std::string diff(const Message& expected, const Message& actual) {
  Differ d;
  std::visit(d, expected, actual);
  return d.out.str();
}

std::optional<DecodeError> decode_message(std::span<const uint8_t> bytes, uint64_t max_message_bytes, Decoded& out,
                                          std::vector<uint8_t>& storage) {
  if (auto err = decode_header(bytes, max_message_bytes, out.header)) return err;
  const size_t available = bytes.size() - kHeaderSize;
  const size_t take = std::min<size_t>(available, out.header.payload_length);
  storage.assign(bytes.begin() + kHeaderSize, bytes.begin() + kHeaderSize + take);
  return decode_payload(out.header, storage, out.message);
}

void put_u16(std::vector<uint8_t>& b, size_t at, uint16_t v) {
  b.at(at) = v & 0xFF;
  b.at(at + 1) = v >> 8;
}
void put_u32(std::vector<uint8_t>& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b.at(at + i) = (v >> (8 * i)) & 0xFF;
}
void put_u64(std::vector<uint8_t>& b, size_t at, uint64_t v) {
  for (int i = 0; i < 8; ++i) b.at(at + i) = (v >> (8 * i)) & 0xFF;
}

}  // namespace dn::protocol::test
