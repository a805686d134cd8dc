#include "pipelines/stages/svgf_stages.hpp"

#include <algorithm>
#include <string>

#include "pipelines/stages/svgf_buffers.hpp"

namespace dn::pipelines::svgf {

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
void add_gbuffer_fill(GraphSpec& g, const SessionConfig& config) {
  const uint32_t levels = gbuffer_levels(config);
  // The grid arguments of every gbuffer_fill pass: its level of the pyramid over the full size.
  auto over = [&](PassSpec& pass, gpu::Extent size, gpu::Extent source, uint32_t level) -> PassSpec& {
    return pass.over_grid(size, source)
        .arg("level", level)
        .arg("factor", kGbufferFactor)
        .arg("width0", config.width)
        .arg("height0", config.height);
  };
  const gpu::Extent full = g.level(kGbufferFactor, 0);
  PassSpec& seed = g.add_pass("gbuffer_seed", "gbuffer_fill");
  seed.bind("depth", "depth")
      .bind("normal", "normal")
      .bind("sample_count", "sample_count")
      .bind("pyramid", kGbufferPyramid)
      .bind("valid", kGbufferValid)
      .mode("seed");
  over(seed, full, full, 0);
  for (uint32_t l = 1; l <= levels; ++l) {
    PassSpec& pull = g.add_pass("gbuffer_pull_" + std::to_string(l), "gbuffer_fill");
    pull.bind("pyramid", kGbufferPyramid).bind("valid", kGbufferValid).mode("pull");
    over(pull, g.level(kGbufferFactor, l), g.level(kGbufferFactor, l - 1), l);
  }
  for (uint32_t l = levels; l-- > 0;) {
    PassSpec& push = g.add_pass("gbuffer_push_" + std::to_string(l), "gbuffer_fill");
    push.bind("pyramid", kGbufferPyramid).bind("valid", kGbufferValid).mode("push");
    over(push, g.level(kGbufferFactor, l), g.level(kGbufferFactor, l + 1), l);
    if (l == 0) push.bind("filled_depth", kFilledDepth).bind("filled_normal", kFilledNormal);
  }
}

}  // namespace dn::pipelines::svgf
