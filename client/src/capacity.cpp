#include "dn/client/capacity.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "dn/client/error.hpp"

namespace dn::client {

namespace {

std::optional<double> find(const protocol::Stats& stats, std::string_view name) {
  for (const auto& v : stats.values)
    if (v.name == name) return v.value;
  return std::nullopt;
}

double require(const protocol::Stats& stats, const std::string& name) {
  if (const auto v = find(stats, name)) return *v;
  throw Error::usage("STATS has no '" + name +
                     "': the pipeline is not offered, or the server predates the capacity figures");
}

// Whole sessions in a quotient; the tolerance keeps 0.6 / 0.3 (1.999...98 in binary) at 2.
uint64_t whole(double v) { return v <= 0 ? 0 : static_cast<uint64_t>(std::floor(v * (1 + 1e-12))); }

}  // namespace

Capacity capacity(const protocol::Stats& stats, std::string_view pipeline, uint32_t width, uint32_t height,
                  double fps) {
  if (width == 0 || height == 0) throw Error::usage("capacity: width and height must be positive");
  if (!std::isfinite(fps) || fps < 0) throw Error::usage("capacity: fps must be a finite number >= 0");
  const std::string prefix = "pipeline." + std::string(pipeline) + ".";
  const double pixels = double(width) * double(height);

  Capacity c;
  c.session_bytes = static_cast<uint64_t>(std::ceil(require(stats, prefix + "device_bytes_fixed") +
                                                    require(stats, prefix + "device_bytes_per_pixel") * pixels));
  const double free_bytes = require(stats, "device_memory_free_bytes");
  const bool within_session_limit = double(c.session_bytes) <= require(stats, "max_session_bytes");
  c.by_memory = within_session_limit && c.session_bytes ? whole(free_bytes / double(c.session_bytes)) : 0;
  c.by_session_limit = whole(require(stats, "max_sessions") - require(stats, "sessions") -
                             require(stats, "sessions_being_built"));
  c.sessions = std::min(c.by_memory, c.by_session_limit);

  if (const auto ms_per_mp = find(stats, prefix + "frame_ms_per_megapixel")) c.frame_ms = *ms_per_mp * pixels / 1e6;
  if (fps > 0 && c.frame_ms) {
    const double idle = std::max(0.0, 1.0 - require(stats, "device_busy_fraction"));
    const double share = fps * *c.frame_ms / 1000.0;  // of the device's time, per session
    c.by_time = share > 0 ? whole(idle / share) : c.by_session_limit;
    c.sessions = std::min(c.sessions, *c.by_time);
  }
  return c;
}

}  // namespace dn::client
