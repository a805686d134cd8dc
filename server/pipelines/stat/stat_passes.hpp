// The passes and checks stat and stat-temporal share (docs/pipelines.md,
// "stat"): the frame's statistics planes, the critical-value table, the
// per-pixel prepare pass and the disc gather.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "pipelines/definitions.hpp"

namespace dn::pipelines {

// Entries of the critical-value tables (the TABLE_SIZE of the passes that read them).
inline constexpr uint32_t kStatTableSize = 1024;
// The largest radius stat_filter_tiled's shared-memory tile serves (its
// APRON): (8 + 2 * 6)^2 texels of 80 B fill lavapipe's 32 KiB.
inline constexpr uint32_t kStatTileApron = 6;

// Where stat_prepare and stat_filter read a pixel's statistics: the frame's
// planes (stat) or the accumulators (stat-temporal), in the planes' layouts.
struct StatSources {
  std::string count, mean, m2, m3;
  std::string raw;  // the raw means that are averaged
  // With demodulated statistics (parameter demodulated), who writes the
  // plane kStatModulation that remodulates the result: stat_prepare from
  // the frame's planes (the sources are the frame's: stat), or a pass before
  // it (stat_temporal, which sees the frame; the accumulators do not).
  bool prepare_modulates = true;
  // stat-temporal: stat_prepare classifies each pixel from "motion" and
  // "albedo" (stat_class.glsl): the filter tests a moving pixel's neighbours
  // by Eq. 14 (their histories may hold what moved over them), and a still
  // pixel the guides do not explain (a metal, a mirror) shows its own mean.
  bool classify = false;
};

// The channels both take besides their own: radiance, albedo, normal and the
// four statistics.
uint64_t stat_channels();
// The plane that remodulates stat_filter's result with demodulated statistics.
inline constexpr const char* kStatModulation = "stat_modulation";
// Declares the frame's planes of stat_channels(), named by their channels'
// names (radiance, albedo, normal, stat_count, ...), and the table
// "stat_t_squared" (t_squared_table at stat's alpha, then at still_alpha for
// two still pixels with statistics of their own); with_statistics false: all
// but the four statistics.
void add_stat_inputs(GraphSpec& g, const SessionConfig& config, bool with_statistics, double still_alpha);
// The four statistics channels' mask.
uint64_t statistics_channels();
// Whether the session declares all four statistics channels (none: false;
// some: check_statistics refuses the session where they are optional).
bool declares_statistics(const SessionConfig& config);
// t^2 of the two-sided Student-t quantile at significance alpha for nu = 1 ..
// kStatTableSize (entry k: nu = k + 1), as the fp32 bytes of a Constant buffer.
std::vector<uint8_t> t_squared_table(double alpha);
// stat_prepare and stat_filter (stat_filter_tiled where it serves) over
// `sources`, writing the output plane. With demodulated statistics the
// filter averages stat_prepare's demodulated means ("stat_value") and
// multiplies by kStatModulation (declared here when prepare_modulates).
void add_stat_filter(GraphSpec& g, const SessionConfig& config, const StatSources& sources);
// The statistics are fp32 only (docs/protocol.md §7.7).
std::optional<ConfigError> check_statistics(const SessionConfig& config);
// check_statistics, and all four statistics or none (where they are optional: stat-temporal).
std::optional<ConfigError> check_optional_statistics(const SessionConfig& config);

}  // namespace dn::pipelines
