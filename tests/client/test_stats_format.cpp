// dn stats: readable numbers with units in stable columns (client/tools/stats_format.hpp).
#include <gtest/gtest.h>

#include <regex>
#include <sstream>

#include "dn/protocol/channels.hpp"
#include "stats_format.hpp"

namespace {

using dn::cli::readable_stat;

std::string shown(const std::string& name, double v) {
  const auto r = readable_stat(name, v);
  return r.unit.empty() ? r.number : r.number + " " + r.unit;
}

TEST(StatsFormat, UnitsFromTheNameAndThreeSignificantDigits) {
  EXPECT_EQ(shown("uptime_s", 12.3456789), "12.3 s");
  EXPECT_EQ(shown("uptime_s", 754.2), "12.6 min");
  EXPECT_EQ(shown("uptime_s", 7300), "2.03 h");
  EXPECT_EQ(shown("uptime_s", 0.25), "250 ms");
  EXPECT_EQ(shown("kernel_compile_ms", 0.0123456), "0.0123 ms");
  EXPECT_EQ(shown("kernel_compile_ms", 12345.678), "12.3 s");
  EXPECT_EQ(shown("pass.filter.mean_ms", 3.14159), "3.14 ms");
  EXPECT_EQ(shown("device_bytes", 123), "123 B");
  EXPECT_EQ(shown("device_bytes", 1234567), "1.23 MB");
  EXPECT_EQ(shown("device_bytes", 999999), "1 MB");
  EXPECT_EQ(shown("bytes_in", 5.5e9), "5.5 GB");
  EXPECT_EQ(shown("session.7.persistent_bytes_per_pixel", 53.3333333), "53.3 B/px");
  EXPECT_EQ(shown("frames_processed", 1234567), "1,234,567");
  EXPECT_EQ(shown("warm_up_done", 1), "1");
  EXPECT_EQ(shown("ratio", 12345.678), "12,300");
  EXPECT_EQ(shown("ratio", 0.333333333), "0.333");
}

// Counts keep every digit whatever their size (%.0f of a whole double is exact).
TEST(StatsFormat, WholeNumbersPrintEveryDigit) {
  EXPECT_EQ(shown("frames_processed", 36028788433223680.0), "36,028,788,433,223,680");
  EXPECT_EQ(shown("frames_processed", 1e15 + 1), "1,000,000,000,000,001");
  EXPECT_EQ(shown("frames_processed", 9007199254740993.0), "9,007,199,254,740,992");  // the double nearest 2^53 + 1
  EXPECT_EQ(shown("frames_processed", 0), "0");
}

// A channel mask comes as two exact halves (server/stats.cpp): _channels_lo
// (bit i = channel id i) and _channels_hi (id 32 + i), each printed as its
// channels' names in the protocol's table order; a bit of no known channel by id.
TEST(StatsFormat, ChannelMasksPrintAsChannelNames) {
  using dn::protocol::ChannelId;
  using dn::protocol::channel_bit;
  const uint64_t svgf = channel_bit(ChannelId::Radiance) | channel_bit(ChannelId::Albedo) |
                        channel_bit(ChannelId::Roughness) | channel_bit(ChannelId::Normal) |
                        channel_bit(ChannelId::Depth) | channel_bit(ChannelId::Motion) |
                        channel_bit(ChannelId::Emission);
  EXPECT_EQ(svgf, 0x3E9u);  // docs/server.md's example
  EXPECT_EQ(shown("pipeline.svgf.reference_channels_lo", double(svgf)),
            "radiance,albedo,roughness,normal,depth,motion,emission");
  EXPECT_EQ(shown("pipeline.svgf.reference_channels_hi", 0), "none");
  // Radiance (id 0) with the sample statistics (51-54): 55 bits, more than a double holds exactly.
  const uint64_t stat = channel_bit(ChannelId::Radiance) | channel_bit(ChannelId::StatCount) |
                        channel_bit(ChannelId::StatMean) | channel_bit(ChannelId::StatM2) | channel_bit(ChannelId::StatM3);
  EXPECT_NE(uint64_t(double(stat)), stat);
  EXPECT_EQ(shown("pipeline.stat.reference_channels_lo", double(stat & 0xFFFFFFFFu)), "radiance");
  EXPECT_EQ(shown("pipeline.stat.reference_channels_hi", double(stat >> 32)), "stat_count,stat_mean,stat_m2,stat_m3");
  EXPECT_EQ(shown("pipeline.x.reference_channels_lo", double(1u << 22)), "channel 22");
  EXPECT_EQ(shown("pipeline.x.reference_channels_hi", double(1u << 28)), "channel 60");
  EXPECT_EQ(shown("pipeline.x.reference_channels_lo", 0.5), "0.5");  // not a mask: a plain number
  EXPECT_EQ(shown("pipeline.x.reference_channels_lo", 0x1p33), "8,589,934,592");  // nor is this
}

TEST(StatsFormat, ReportAlignsNumbersRightAndLeavesNoTrailingBlanks) {
  const std::vector<dn::protocol::StatValue> values = {
      {"uptime_s", 12.3456}, {"frames_processed", 1234567}, {"device_bytes", 2.5e6}, {"warm_up_done", 1}};
  const std::string report = dn::cli::stats_report(values);
  EXPECT_EQ(report,
            "uptime_s               12.3 s\n"
            "frames_processed  1,234,567\n"
            "device_bytes            2.5 MB\n"
            "warm_up_done              1\n");
  // What bench/lib/bench_server.sh waits for.
  EXPECT_TRUE(std::regex_search(report, std::regex("(^|\n)warm_up_done +1\n")));
  // A channel list starts at the number column and does not widen it.
  EXPECT_EQ(dn::cli::stats_report({{"pipeline.a.reference_channels_lo", 9}, {"frames_processed", 12}}),
            "pipeline.a.reference_channels_lo  radiance,albedo\n"
            "frames_processed                  12\n");
  EXPECT_EQ(dn::cli::stats_report_raw({{"frames_processed", 36028788433223680.0}}),
            "frames_processed  36028788433223680\n");
  EXPECT_EQ(dn::cli::stats_report_raw({{"uptime_s", 0.1}, {"warm_up_done", 1}}),
            "uptime_s      0.10000000000000001\n"
            "warm_up_done                    1\n");
}

}  // namespace
