// image's description: radiance, with albedo, normal and depth where the
// renderer has them; its own parameter group.
#include "descriptions.hpp"

namespace dn {
namespace {

using protocol::ChannelId;

TEST(ImageDescription, RadianceWithOptionalGuidesAndItsOwnParameters) {
  const auto& d = test::description("image");
  EXPECT_EQ(d.required_channels, test::bits({ChannelId::Radiance}));
  EXPECT_EQ(d.optional_channels, test::bits({ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth}));
  EXPECT_EQ(test::parameter_names(d), (std::vector<std::string>{"iterations", "phi_luminance", "phi_normal", "phi_depth",
                                                                "phi_albedo", "noise_cap", "harm_guard",
                                                                "noise_estimate"}));
}

}  // namespace
}  // namespace dn
