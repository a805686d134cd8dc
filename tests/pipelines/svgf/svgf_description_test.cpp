// svgf's and svgf-fb's descriptions: the channels WELCOME lists and the parameters.
#include "descriptions.hpp"

namespace dn {
namespace {

using protocol::ChannelId;
using test::bits;

TEST(SvgfDescription, GBufferRequiredLightingInEitherFormOptional) {
  const auto& svgf = test::description("svgf");
  EXPECT_EQ(svgf.required_channels, bits({ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion}));
  // Radiance, or the split pair in either form (the either/or rule is checked by validate()).
  EXPECT_EQ(svgf.optional_channels,
            bits({ChannelId::Radiance, ChannelId::Diffuse, ChannelId::Specular, ChannelId::DiffuseLighting,
                  ChannelId::SpecularLighting, ChannelId::SpecularAlbedo, ChannelId::Emission, ChannelId::Roughness}) |
                test::extra_sample_bits());
  EXPECT_EQ(test::parameter_names(svgf), test::kSvgfParameterNames);
  EXPECT_EQ(test::default_of(svgf, "alpha_colour"), 0.05);
  EXPECT_EQ(test::default_of(svgf, "atrous_iterations"), 4.0);
}

// svgf-fb: split lighting with F0 and roughness (diffuse in either form); svgf's parameters.
TEST(SvgfFbDescription, SplitLightingWithF0AndRoughness) {
  const auto& fb = test::description("svgf-fb");
  EXPECT_EQ(fb.required_channels, bits({ChannelId::Specular, ChannelId::Albedo, ChannelId::SpecularF0, ChannelId::Roughness,
                                        ChannelId::Normal, ChannelId::Depth, ChannelId::Motion}));
  EXPECT_EQ(fb.optional_channels,
            bits({ChannelId::Diffuse, ChannelId::DiffuseLighting, ChannelId::Emission}) | test::extra_sample_bits());
  EXPECT_EQ(test::parameter_names(fb), test::kSvgfParameterNames);
}

}  // namespace
}  // namespace dn
