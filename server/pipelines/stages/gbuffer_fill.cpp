#include "pipelines/stages/svgf_stages.hpp"

#include <algorithm>
#include <array>
#include <string>

#include "pipelines/stages/svgf_buffers.hpp"

namespace dn::pipelines::svgf {

using protocol::ChannelId;

namespace {

// The number of levels above level 0 of the 3x3 pyramid: down to one pixel.
uint32_t gbuffer_levels(const SessionConfig& config) {
  uint32_t levels = 0;
  for (uint32_t side = std::max(config.width, config.height); side > 1; side = (side + kGbufferFactor - 1) / kGbufferFactor)
    ++levels;
  return levels;
}

}  // namespace

// gbuffer_fill: seed level 0 from the planes, pull to the coarsest level,
// push back down; the push at level 0 writes the filled planes.
void add_gbuffer_fill(GraphSpec& g, const SessionConfig& config, ChannelId mask) {
  const uint32_t levels = gbuffer_levels(config);
  auto args = [&](uint32_t level) {
    return std::array<uint32_t, 4>{level, kGbufferFactor, config.width, config.height};
  };
  const gpu::Extent full = g.level(kGbufferFactor, 0);
  g.add_pass("gbuffer_seed", "gbuffer_fill")
      .bind("depth", "depth")
      .bind("normal", "normal")
      .bind("sample_count", "sample_count")
      .bind("pyramid", kGbufferPyramid)
      .bind("valid", kGbufferValid)
      .set("MODE", 0u)
      .set("DEPTH_HALF", is_half(channel_format(config, ChannelId::Depth)))
      .set("NORMAL_HALF", is_half(channel_format(config, ChannelId::Normal)))
      .set("SAMPLE_COUNT_HALF", is_half(channel_format(config, mask)))
      .over_grid(full, full, args(0));
  for (uint32_t l = 1; l <= levels; ++l)
    g.add_pass("gbuffer_pull_" + std::to_string(l), "gbuffer_fill")
        .bind("pyramid", kGbufferPyramid)
        .bind("valid", kGbufferValid)
        .set("MODE", 1u)
        .over_grid(g.level(kGbufferFactor, l), g.level(kGbufferFactor, l - 1), args(l));
  for (uint32_t l = levels; l-- > 0;) {
    PassSpec& push = g.add_pass("gbuffer_push_" + std::to_string(l), "gbuffer_fill");
    push.bind("pyramid", kGbufferPyramid)
        .bind("valid", kGbufferValid)
        .set("MODE", 2u)
        .over_grid(g.level(kGbufferFactor, l), g.level(kGbufferFactor, l + 1), args(l));
    if (l == 0) push.bind("filled_depth", kFilledDepth).bind("filled_normal", kFilledNormal);
  }
}

}  // namespace dn::pipelines::svgf
