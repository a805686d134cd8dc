// reflect's description: svgf-fb's channels plus the reflection features, svgf's parameters plus its own.
#include "descriptions.hpp"

namespace dn {
namespace {

using protocol::ChannelId;
using test::bits;

TEST(ReflectDescription, SvgfFbsChannelsPlusTheReflectionFeatures) {
  const auto& reflect = test::description("reflect");
  const auto& fb = test::description("svgf-fb");
  const uint64_t features = bits({ChannelId::Position, ChannelId::ReflectionPosition, ChannelId::ReflectionAlbedo,
                                  ChannelId::ReflectionNormal, ChannelId::ReflectionDepth,
                                  ChannelId::ReflectionDirection, ChannelId::ReflectionDistance});
  EXPECT_EQ(reflect.required_channels, fb.required_channels | features);
  EXPECT_EQ(reflect.optional_channels, fb.optional_channels | bits({ChannelId::ReflectionFootprint}));
  std::vector<std::string> expected = test::kSvgfParameterNames;
  // The stages' specular group (the specular chain's blend floor), then its own.
  expected.insert(expected.end(), {"alpha_specular", "mirror_roughness", "glossy_roughness", "specular_history",
                                   "virtual_start", "mirror_match_threshold", "footprint_omega", "firefly_median"});
  EXPECT_EQ(test::parameter_names(reflect), expected);
}

}  // namespace
}  // namespace dn
