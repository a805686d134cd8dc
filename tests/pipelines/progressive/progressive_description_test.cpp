// progressive's description: svgf's channels without roughness and extra
// samples, plus sample_count; svgf's parameters with paper 004's defaults,
// and its own.
#include "descriptions.hpp"

#include "pipelines/parameters.hpp"

namespace dn {
namespace {

using protocol::ChannelId;

TEST(ProgressiveDescription, SvgfsChannelsPlusSampleCount) {
  const auto& progressive = test::description("progressive");
  const auto& svgf = test::description("svgf");
  EXPECT_EQ(progressive.required_channels, svgf.required_channels);
  EXPECT_EQ(progressive.optional_channels,
            (svgf.optional_channels & ~(test::bits({ChannelId::Roughness}) | test::extra_sample_bits())) |
                test::bits({ChannelId::SampleCount}));
}

TEST(ProgressiveDescription, SvgfsParametersWithPaper004sDefaultsAndItsOwn) {
  const auto& progressive = test::description("progressive");
  std::vector<std::string> expected = test::kSvgfParameterNames;
  // The stages' atrous group (the luminance weight's other forms), then its own.
  expected.insert(expected.end(), {"sigma_luminance", "epsilon_luminance", "luminance_min_age", "luminance_ramp_in",
                                   "step_order", "luminance_form", "display_lag", "sparse_gbuffer"});
  EXPECT_EQ(test::parameter_names(progressive), expected);
  EXPECT_EQ(test::default_of(progressive, "alpha_colour"), 0.1);
  EXPECT_EQ(test::default_of(progressive, "atrous_iterations"), 5.0);
  EXPECT_EQ(test::default_of(progressive, "phi_normal"), 64.0);
  EXPECT_EQ(test::default_of(progressive, "clip_roughness"), 0.0);
  // The resolved block the shaders read: atrous_iterations is the fourth row of svgf's group.
  EXPECT_EQ(pipelines::resolve_parameters("progressive", {})[3], 5.0f);
}

}  // namespace
}  // namespace dn
