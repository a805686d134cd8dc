// stat's and stat-temporal's descriptions: channels and parameters.
#include "descriptions.hpp"

namespace dn {
namespace {

using protocol::ChannelId;
using test::bits;

const uint64_t kStatistics = bits({ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3});
const std::vector<std::string> kStatParameters = {"alpha", "radius", "sigma_spatial", "sigma_albedo", "sigma_normal",
                                                  "variance_floor", "membership", "asymmetric", "membership_falloff",
                                                  "demodulated", "pool_single", "spatial_shrink_from"};

// The raw mean, the guides and the four sample statistics (docs/protocol.md §7.7), nothing optional.
TEST(StatDescription, RawMeanGuidesAndTheFourStatistics) {
  const auto& stat = test::description("stat");
  EXPECT_EQ(stat.required_channels, bits({ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal}) | kStatistics);
  EXPECT_EQ(stat.optional_channels, 0u);
  EXPECT_EQ(test::parameter_names(stat), kStatParameters);
}

// stat's channels plus depth and motion (reprojection), the four statistics
// optional (without them the radiance is one sample per frame); stat's
// parameters and its own.
TEST(StatTemporalDescription, StatsChannelsPlusReprojectionStatisticsOptional) {
  const auto& temporal = test::description("stat-temporal");
  EXPECT_EQ(temporal.required_channels, (test::description("stat").required_channels & ~kStatistics) |
                                            bits({ChannelId::Depth, ChannelId::Motion}));
  EXPECT_EQ(temporal.optional_channels, kStatistics);
  std::vector<std::string> expected = kStatParameters;
  expected.insert(expected.end(), {"still_alpha", "history_alpha", "fading"});
  EXPECT_EQ(test::parameter_names(temporal), expected);
}

}  // namespace
}  // namespace dn
