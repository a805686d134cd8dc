// dn stats: readable numbers with units in stable columns (client/tools/stats_format.hpp).
#include <gtest/gtest.h>

#include <regex>
#include <sstream>

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
  EXPECT_EQ(dn::cli::stats_report_raw({{"uptime_s", 0.1}, {"warm_up_done", 1}}),
            "uptime_s      0.10000000000000001\n"
            "warm_up_done                    1\n");
}

}  // namespace
