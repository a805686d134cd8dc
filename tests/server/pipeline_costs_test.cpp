// The per-pipeline memory model STATS reports: fixed + per_pixel * pixels must
// give what prepare() estimates for the reference session at any size, and
// bound every session of the pipeline that declares fewer channels.
#include <gtest/gtest.h>

#include <algorithm>
#include <variant>

#include "server/capacity/pipeline_costs.hpp"

namespace dn::server {
namespace {

uint64_t estimate(const pipelines::SessionConfig& config) {
  auto prepared = pipelines::prepare(config);
  const auto* ready = std::get_if<pipelines::PreparedPipeline>(&prepared);
  if (!ready) ADD_FAILURE() << config.pipeline << ": " << std::get<pipelines::ConfigError>(prepared).message;
  return ready ? ready->device_bytes() : 0;
}

const PipelineCost* cost_of(const std::string& name) {
  for (const auto& c : pipeline_costs())
    if (c.pipeline == name) return &c;
  return nullptr;
}

TEST(PipelineCosts, EveryPipelineHasAModel) {
  for (const auto& p : pipelines::available_pipelines()) {
    const PipelineCost* c = cost_of(p.name);
    ASSERT_NE(c, nullptr) << p.name;
    EXPECT_GT(c->bytes_per_pixel, 0) << p.name;
    EXPECT_GE(c->fixed_bytes, 0) << p.name;
  }
}

TEST(PipelineCosts, ModelMatchesTheEstimateAtSizesItWasNotFittedTo) {
  const std::pair<uint32_t, uint32_t> sizes[] = {{1, 1}, {37, 19}, {256, 144}, {333, 77}, {1920, 1080}};
  for (const auto& p : pipelines::available_pipelines())
    for (const auto& [w, h] : sizes) {
      const PipelineCost& c = *cost_of(p.name);
      const double model = c.fixed_bytes + c.bytes_per_pixel * double(w) * double(h);
      EXPECT_DOUBLE_EQ(model, double(estimate(reference_session(p, w, h)))) << p.name << " at " << w << "x" << h;
    }
}

TEST(PipelineCosts, F16ChannelsAndOutputCostNoMoreThanTheReference) {
  for (const auto& p : pipelines::available_pipelines()) {
    const uint64_t reference = estimate(reference_session(p, 256, 144));
    pipelines::SessionConfig half = reference_session(p, 256, 144);
    half.output_format = protocol::Format::F16;
    EXPECT_LE(estimate(half), reference) << p.name;
    for (size_t i = 0; i < half.channels.size(); ++i) {  // each channel that may be F16 (stat_count may not)
      pipelines::SessionConfig one = reference_session(p, 256, 144);
      one.channels[i].format = protocol::Format::F16;
      auto prepared = pipelines::prepare(one);
      if (const auto* ready = std::get_if<pipelines::PreparedPipeline>(&prepared))
        EXPECT_LE(ready->device_bytes(), reference) << p.name << " channel " << i;
    }
  }
}

TEST(PipelineCosts, SvgfKeepsRadianceAndItsGuides) {
  // svgf refuses radiance with the diffuse + specular split: the reference keeps
  // radiance (first in channel order) and every guide it requires.
  const auto& all = pipelines::available_pipelines();
  const auto svgf = std::find_if(all.begin(), all.end(), [](const auto& d) { return d.name == "svgf"; });
  ASSERT_NE(svgf, all.end());
  const uint64_t mask = cost_of("svgf")->reference_channels;
  EXPECT_TRUE(mask & protocol::channel_bit(protocol::ChannelId::Radiance));
  EXPECT_FALSE(mask & protocol::channel_bit(protocol::ChannelId::Diffuse));
  EXPECT_FALSE(mask & protocol::channel_bit(protocol::ChannelId::Specular));
  EXPECT_EQ(mask & svgf->required_channels, svgf->required_channels);
}

}  // namespace
}  // namespace dn::server
