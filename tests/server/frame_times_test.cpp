// The measured frame times behind pipeline.<name>.frame_ms_per_megapixel and
// device_busy_fraction, against hand-computed medians and sums.
#include <gtest/gtest.h>

#include "server/capacity/frame_times.hpp"

namespace dn::server {
namespace {

using namespace std::chrono_literals;

std::vector<pipelines::PassTiming> frame(double upload, double pass, double download) {
  return {{"upload", upload}, {"pass", pass}, {"download", download}};
}

TEST(FrameTimes, NothingBeforeTheFirstFrame) {
  FrameTimes t;
  EXPECT_FALSE(t.ms_per_megapixel("svgf").has_value());
  EXPECT_EQ(t.frames_measured("svgf"), 0u);
  EXPECT_EQ(t.busy_fraction(), 0.0);
}

TEST(FrameTimes, MedianPerMegapixelOverTheFramesSummed) {
  FrameTimes t;
  const auto now = FrameTimes::Clock::now();
  t.add("svgf", 500'000, frame(1, 2, 1), now);   // 4 ms on 0.5 MP: 8 ms/MP
  t.add("svgf", 2'000'000, frame(2, 6, 2), now);  // 10 ms on 2 MP: 5 ms/MP
  t.add("svgf", 1'000'000, frame(0, 30, 0), now);  // 30 ms/MP, an outlier the median ignores
  t.add("passthrough", 1'000'000, frame(0, 1, 0), now);
  EXPECT_DOUBLE_EQ(*t.ms_per_megapixel("svgf"), 8.0);
  EXPECT_EQ(t.frames_measured("svgf"), 3u);
  t.add("svgf", 1'000'000, frame(0, 6, 0), now);  // even count: (6 + 8) / 2
  EXPECT_DOUBLE_EQ(*t.ms_per_megapixel("svgf"), 7.0);
  EXPECT_DOUBLE_EQ(*t.ms_per_megapixel("passthrough"), 1.0);
  EXPECT_EQ(t.pipelines(), (std::vector<std::string>{"passthrough", "svgf"}));
}

TEST(FrameTimes, OnlyTheLastFramesCount) {
  FrameTimes t;
  const auto now = FrameTimes::Clock::now();
  for (size_t i = 0; i < FrameTimes::kFramesPerPipeline; ++i) t.add("p", 1'000'000, frame(0, 100, 0), now);
  for (size_t i = 0; i < FrameTimes::kFramesPerPipeline; ++i) t.add("p", 1'000'000, frame(0, 3, 0), now);
  EXPECT_DOUBLE_EQ(*t.ms_per_megapixel("p"), 3.0);
  EXPECT_EQ(t.frames_measured("p"), FrameTimes::kFramesPerPipeline);
}

TEST(FrameTimes, BusyFractionOfTheLastTenSeconds) {
  FrameTimes t;
  const auto t0 = FrameTimes::Clock::now();
  t.add("a", 100, frame(100, 200, 0), t0);     // 300 ms
  t.add("b", 100, frame(0, 700, 0), t0 + 5s);  // 700 ms
  EXPECT_DOUBLE_EQ(t.busy_fraction(t0 + 6s), 1000.0 / 10000.0);
  EXPECT_DOUBLE_EQ(t.busy_fraction(t0 + 12s), 700.0 / 10000.0);  // the first left the window
  EXPECT_DOUBLE_EQ(t.busy_fraction(t0 + 16s), 0.0);
}

TEST(FrameTimes, AZeroSizeFrameIsIgnored) {
  FrameTimes t;
  t.add("p", 0, frame(1, 1, 1));
  EXPECT_EQ(t.frames_measured("p"), 0u);
}

}  // namespace
}  // namespace dn::server
