// accumulate's description: radiance and the reprojection's guides, four parameters.
#include "descriptions.hpp"

namespace dn {
namespace {

using protocol::ChannelId;

TEST(AccumulateDescription, RadianceWithReprojectionGuidesAndFourParameters) {
  const auto& d = test::description("accumulate");
  EXPECT_EQ(d.required_channels,
            test::bits({ChannelId::Radiance, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion}));
  for (const auto& p : d.parameters) {
    EXPECT_LE(p.min_value, p.default_value) << p.name;
    EXPECT_LE(p.default_value, p.max_value) << p.name;
    EXPECT_FALSE(p.description.empty()) << p.name;
  }
  EXPECT_EQ(test::parameter_names(d),
            (std::vector<std::string>{"alpha_min", "max_history", "depth_tolerance", "normal_threshold"}));
}

}  // namespace
}  // namespace dn
