#include "pipelines/progressive/gbuffer_fill.hpp"

#include <algorithm>
#include <string>

namespace dn::pipelines {
namespace {

// The packed 3x3 pyramid of vec4(normal, depth) and its validity (uint), and
// the filled planes (gbuffer_fill.pass sizes them).
constexpr const char* kGbufferPyramid = "gbuffer_pyramid";
constexpr const char* kGbufferValid = "gbuffer_valid";
constexpr const char* kFilledDepth = "gbuffer_depth";
constexpr const char* kFilledNormal = "gbuffer_normal";
constexpr uint32_t kGbufferFactor = 3;

// The number of levels above level 0 of the 3x3 pyramid: down to one pixel.
uint32_t gbuffer_levels(const SessionConfig& config) {
  uint32_t levels = 0;
  for (uint32_t side = std::max(config.width, config.height); side > 1; side = (side + kGbufferFactor - 1) / kGbufferFactor)
    ++levels;
  return levels;
}

}  // namespace

SignalFeatures add_gbuffer_fill(GraphSpec& g, const SessionConfig& config) {
  const uint64_t elements = gpu::pyramid_pixels(g.width, g.height, kGbufferFactor);
  g.add_scratch_elements(kGbufferPyramid, elements, 16);
  g.add_scratch_elements(kGbufferValid, elements, 4);
  g.add_scratch(kFilledDepth);
  g.add_scratch(kFilledNormal);
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
  return {kFilledDepth, kFilledNormal};
}

}  // namespace dn::pipelines
