// RESULT.samples' histogram on the host: every count falls in the bin whose
// floor is at most it and within 1/16 of it, bins are contiguous, and the
// decoded median is the lower median's bin floor.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "pipelines/sample_summary.hpp"

namespace dn::pipelines {
namespace {

TEST(SampleBins, EveryCountFallsInTheBinBelowItWithinASixteenth) {
  for (uint32_t n = 0; n < (1u << 21); n += 1 + n / 97) {
    const uint32_t b = sample_bin(n);
    ASSERT_LT(b, kSampleBins) << n;
    const uint32_t floor = sample_bin_floor(b);
    ASSERT_LE(floor, n) << n;
    if (n < 32) ASSERT_EQ(floor, n);
    ASSERT_GE(double(floor), double(n) * (1.0 - 1.0 / 16.0)) << n;
    if (b + 1 < kSampleBins) ASSERT_LT(n, sample_bin_floor(b + 1)) << n;
  }
  EXPECT_EQ(sample_bin(0xffffffffu), kSampleBins - 1);
}

std::vector<uint8_t> summary_bytes(uint32_t min, const std::vector<std::pair<uint32_t, uint32_t>>& counts) {
  std::vector<uint32_t> words(1 + kSampleBins, 0);
  words[0] = 0xffffffffu - min;
  for (auto [count, pixels] : counts) words[1 + sample_bin(count)] += pixels;
  std::vector<uint8_t> bytes(words.size() * 4);
  std::memcpy(bytes.data(), words.data(), bytes.size());
  return bytes;
}

TEST(SampleSummary, DecodesTheMinimumAndTheLowerMedian) {
  EXPECT_FALSE(decode_sample_summary(std::vector<uint8_t>(4 * (1 + kSampleBins), 0))) << "no pixel counted";
  auto s = decode_sample_summary(summary_bytes(1, {{1, 3}, {5, 2}, {9, 4}}));  // 1 1 1 5 5 9 9 9 9
  ASSERT_TRUE(s);
  EXPECT_EQ(s->min, 1u);
  EXPECT_EQ(s->median, 5u);
  s = decode_sample_summary(summary_bytes(2, {{2, 2}, {7, 2}}));  // 2 2 7 7: the lower median
  EXPECT_EQ(s->median, 2u);
  s = decode_sample_summary(summary_bytes(1000, {{1000, 5}}));  // one bin: [992, 1024), min inside it
  EXPECT_EQ(s->min, 1000u);
  EXPECT_EQ(s->median, 1000u) << "the median is never below the minimum";
}

}  // namespace
}  // namespace dn::pipelines
