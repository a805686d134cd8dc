#include "pipelines/stages/svgf_stages.hpp"

#include <utility>

namespace dn::pipelines::svgf {

namespace {

// The register block: one invocation filters kBlock^2 pixels (svgf_atrous.comp's BLOCK).
constexpr uint32_t kBlock = 4;

}  // namespace

// Every signal in the same passes (the joint chain: the guide's loads and
// geometric weights shared).
std::vector<std::string> add_atrous(GraphSpec& g, const SessionConfig& config, const AtrousStage& stage) {
  std::vector<SignalChain> ping = stage.signals;  // illum and other swap after every iteration
  const SignalChain& first = ping[0];
  const bool two = ping.size() > 1;
  const uint32_t iterations = static_cast<uint32_t>(stage.levels.size());
  for (uint32_t i = 0; i < iterations; ++i) {
    const uint32_t level = stage.levels[i];
    const bool feedback = i == stage.feedback_tap;
    PassSpec& atrous = g.add_pass("svgf_atrous_" + std::to_string(i), "svgf_atrous");
    atrous.bind("guide", first.guide)
        .bind("src", first.illum)
        .bind("dst", first.other)
        .bind("temporal", first.temporal)
        .set("STEP", 1u << level)
        .set("FEEDBACK", feedback)
        .set("BLOCK", kBlock)
        .set("CLASS_EDGES", stage.class_edges)
        .set("KERNEL_RADIUS", stage.kernel_radius)
        .set("LUMINANCE_VARIANCE", stage.luminance_variance)
        .set("AGE_GATED_LUMINANCE", stage.age_gated_luminance)
        .set("DISPLAY_FILL", stage.display_fill && i + 1 == iterations)
        .set("SIGNALS", static_cast<uint32_t>(ping.size()))
        .set("NORMAL_POWER", static_cast<uint32_t>(stage.normal_power))
        .set("LUMINANCE_RAMP", stage.luminance_ramp);
    if (feedback) atrous.bind("colour_history", first.colour_history);
    if (two) {
      const SignalChain& second = ping[1];
      atrous.bind("src2", second.illum).bind("dst2", second.other);
      if (feedback) atrous.bind("colour_history2", second.colour_history);
      bind_second_geometry(atrous, first, second);
    }
    if (feedback && !stage.validity_mask.empty()) bind_validity_mask(atrous, stage.validity_mask);
    if (!stage.bandwidth.empty()) atrous.bind("bandwidth", stage.bandwidth).set("SPATIAL_BANDWIDTH", 1u);
    // Grid of svgf_atrous.comp: (ceil(W / span) * step) x (ceil(H / span) * step), span = step * block.
    const uint64_t step = uint64_t{1} << level, span = step * kBlock;
    atrous.invocations = ((config.width + span - 1) / span * step) * ((config.height + span - 1) / span * step);
    for (size_t s = 0; s < ping.size(); ++s) {
      std::swap(ping[s].illum, ping[s].other);
      if (i == 0 && !stage.guard_partners.empty()) ping[s].other = stage.guard_partners[s];
    }
  }
  std::vector<std::string> results;
  for (const SignalChain& s : ping) results.push_back(s.illum);
  return results;
}

}  // namespace dn::pipelines::svgf
