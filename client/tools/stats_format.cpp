#include "stats_format.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include "dn/protocol/channels.hpp"
#include "server_info.hpp"

namespace dn::cli {

namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// "1234567" -> "1,234,567"; v is a whole number, every digit printed (%.0f is exact).
std::string grouped(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.0f", std::fabs(v));
  std::string digits = buf, out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return (v < 0 ? "-" : "") + out;
}

double round3(double v) {
  if (v == 0.0 || !std::isfinite(v)) return v;
  const double scale = std::pow(10.0, std::floor(std::log10(std::fabs(v))) - 2.0);
  return std::round(v / scale) * scale;
}

// Three significant digits, never in exponent form from 1000 up: 12345.6 -> "12,300".
std::string significant3(double v) {
  if (!std::isfinite(v)) return v != v ? "nan" : (v < 0 ? "-inf" : "inf");
  if (std::fabs(round3(v)) >= 1000.0) return grouped(round3(v));
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

ReadableValue duration_ms(double ms) {
  if (std::fabs(ms) >= 1000.0) return {significant3(ms / 1000.0), "s"};
  return {significant3(ms), "ms"};
}

ReadableValue duration_s(double s) {
  const double a = std::fabs(s);
  if (a < 1.0) return duration_ms(s * 1000.0);
  if (a < 60.0) return {significant3(s), "s"};
  if (a < 3600.0) return {significant3(s / 60.0), "min"};
  if (a < 86400.0) return {significant3(s / 3600.0), "h"};
  return {significant3(s / 86400.0), "d"};
}

ReadableValue bytes(double b) {
  static const char* const units[] = {"B", "kB", "MB", "GB", "TB", "PB"};
  size_t u = 0;
  // Round first, so 999,999 B reads 1 MB rather than 1,000 kB.
  while (u + 1 < std::size(units) && std::fabs(round3(b)) >= 1000.0) {
    b /= 1000.0;
    ++u;
  }
  return {u == 0 ? grouped(std::round(b)) : significant3(b), units[u]};
}

// A channel mask as names ("radiance,albedo"), bit i being channel id
// first_id + i; a bit no channel of this client's protocol has (a newer
// server's) as "channel <id>".
ReadableValue channel_names(double mask_value, uint32_t first_id) {
  const uint64_t mask = static_cast<uint64_t>(mask_value) << first_id;
  uint64_t known = 0;
  for (const auto& c : protocol::kChannels)
    if (static_cast<uint32_t>(c.id) < protocol::kChannelIdLimit) known |= protocol::channel_bit(c.id);
  std::string names = mask & known ? channel_set(mask & known) : "";
  for (uint32_t id = 0; id < 64; ++id)
    if ((mask & ~known) >> id & 1u) names += (names.empty() ? "channel " : ",channel ") + std::to_string(id);
  return {names.empty() ? "none" : names, "", true};
}

bool is_whole(double v) { return std::isfinite(v) && v == std::round(v); }

template <class Format>
std::string report(const std::vector<protocol::StatValue>& values, Format&& format) {
  std::vector<ReadableValue> shown;
  size_t name_width = 0, number_width = 0;
  for (const auto& v : values) {
    shown.push_back(format(v));
    name_width = std::max(name_width, v.name.size());
    if (!shown.back().words) number_width = std::max(number_width, shown.back().number.size());
  }
  std::string out;
  for (size_t i = 0; i < values.size(); ++i) {
    std::string line = values[i].name;
    const size_t pad = shown[i].words ? 0 : number_width - shown[i].number.size();
    line.resize(name_width + 2 + pad, ' ');
    line += shown[i].number;
    if (!shown[i].unit.empty()) line += " " + shown[i].unit;
    out += line + "\n";
  }
  return out;
}

}  // namespace

ReadableValue readable_stat(const std::string& name, double value) {
  if (ends_with(name, "_bytes_per_pixel")) return {significant3(value), "B/px"};
  if (ends_with(name, "_bytes") || name.rfind("bytes_", 0) == 0) return bytes(value);  // device_bytes, bytes_in
  if (ends_with(name, "_ms")) return duration_ms(value);
  if (ends_with(name, "_s")) return duration_s(value);
  // A channel mask comes in halves of 32 bits (STATS values are doubles): ids 0-31 and 32-63.
  const bool mask_half = is_whole(value) && value >= 0 && value < 0x1p32;
  if (ends_with(name, "_channels_lo") && mask_half) return channel_names(value, 0);
  if (ends_with(name, "_channels_hi") && mask_half) return channel_names(value, 32);
  if (is_whole(value)) return {grouped(value), ""};
  return {significant3(value), ""};
}

std::string stats_report(const std::vector<protocol::StatValue>& values) {
  return report(values, [](const protocol::StatValue& v) { return readable_stat(v.name, v.value); });
}

std::string stats_report_raw(const std::vector<protocol::StatValue>& values) {
  return report(values, [](const protocol::StatValue& v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", v.value);
    return ReadableValue{buf, ""};
  });
}

}  // namespace dn::cli
