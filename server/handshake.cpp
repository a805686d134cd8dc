#include "server/handshake.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "dn/protocol/codec.hpp"  // max_payload_bytes
#include "pipelines/auto_choice.hpp"
#include "pipelines/pipeline.hpp"
#include "server/log.hpp"

namespace dn::server {
namespace {

constexpr size_t kMaxDescriptionBytes = 512;  // docs/protocol.md §4.2

// Cut at a UTF-8 character boundary so the result stays valid UTF-8.
std::string clip_utf8(const std::string& s, size_t max_bytes) {
  if (s.size() <= max_bytes) return s;
  size_t n = max_bytes;
  while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;
  return s.substr(0, n);
}

// The wire carries finite bounds only: an open end is the largest double.
double finite_bound(double v) {
  if (std::isfinite(v)) return v;
  return v < 0 ? std::numeric_limits<double>::lowest() : std::numeric_limits<double>::max();
}

protocol::ParameterInfo to_wire(const pipelines::ParameterInfo& p) {
  return {p.name,  p.default_value, finite_bound(p.min_value), finite_bound(p.max_value),
          p.integer, clip_utf8(p.description, kMaxDescriptionBytes)};
}

// WELCOME payload size by the layout of docs/protocol.md §5.2.
uint64_t payload_bytes(const protocol::Welcome& w) {
  uint64_t n = 2 + w.server_version.size() + 2 + w.device_name.size() + 32 + 2;
  for (const auto& p : w.pipelines) n += 2 + p.name.size() + 16;
  if (!w.has_parameters) return n;
  n += 2;
  for (const auto& p : w.pipelines) {
    n += 2;
    for (const auto& q : p.parameters) n += 2 + q.name.size() + 3 * 8 + 1 + 2 + q.description.size();
  }
  return n;
}

}  // namespace

protocol::Welcome make_welcome(const ServerOptions& options, const std::string& device_name, uint8_t client_minor) {
  protocol::Welcome w;
  w.server_version = "dnserver 0.1.0";
  w.device_name = device_name;
  w.limits.max_message_bytes = options.max_message_bytes;
  w.limits.max_session_bytes = options.max_session_bytes;
  w.limits.max_sessions = options.max_sessions;
  w.limits.max_width = options.max_width;
  w.limits.max_height = options.max_height;
  w.limits.max_frames_in_flight = options.max_frames_in_flight;
  // A 1.0 client gets the 1.0 payload, and every client only the channel ids
  // its version defines (docs/protocol.md §10); a pipeline that requires one
  // it does not know is not offered to it.
  w.has_parameters = client_minor >= 1;
  const uint64_t known = protocol::channels_defined_in(std::min(client_minor, protocol::kVersionMinor));
  for (const auto& p : pipelines::available_pipelines()) {
    if (p.required_channels & ~known) continue;
    protocol::PipelineInfo info{p.name, p.required_channels, p.optional_channels & known, {}};
    if (w.has_parameters)
      for (const auto& q : p.parameters) info.parameters.push_back(to_wire(q));
    w.pipelines.push_back(std::move(info));
  }
  if (client_minor >= protocol::kAutoMinor) {  // "auto" last: it takes no parameters
    const pipelines::PipelineDescription a = pipelines::auto_description();
    w.pipelines.push_back({a.name, a.required_channels, a.optional_channels & known, {}});
  }
  // WELCOME must stay within its 65536-byte payload limit. The table is far
  // below it (a few KiB); should it ever grow past, names and ranges matter
  // more than prose: the descriptions go.
  if (w.has_parameters &&
      payload_bytes(w) > protocol::max_payload_bytes(protocol::MessageType::Welcome, UINT64_MAX)) {
    log::warn("welcome.descriptions_dropped", {{"reason", "parameter tables exceed the WELCOME size limit"}});
    for (auto& p : w.pipelines)
      for (auto& q : p.parameters) q.description.clear();
  }
  return w;
}

}  // namespace dn::server
