#include "pipelines/stages/svgf_stages.hpp"

#include <algorithm>

#include "pipelines/stages/svgf_buffers.hpp"

namespace dn::pipelines::svgf {

using protocol::ChannelId;

// Every signal in the same passes (the joint chain: the guide's loads and
// geometric weights shared).
std::vector<std::string> add_atrous(GraphSpec& g, const SessionConfig& config, const SvgfVariant& v) {
  std::vector<SignalBuffers> buffers;
  for (size_t i = 0; i < v.signals.size(); ++i) buffers.push_back(signal_buffers(v, i));
  const bool two = v.signals.size() > 1;
  const SvgfSignal& last = v.signals.back();
  const uint32_t tap = std::min(v.feedback_tap, v.iterations ? v.iterations - 1 : 0u);
  for (uint32_t i = 0; i < v.iterations; ++i) {
    const uint32_t level = step_level(v.steps, i, v.iterations);
    PassSpec& atrous = g.add_pass("svgf_atrous_" + std::to_string(i), "svgf_atrous");
    atrous.bind("guide", buffers[0].guide)
        .bind("src", buffers[0].illum)
        .bind("dst", buffers[0].other)
        .bind("temporal", buffers[0].temporal)
        .set("STEP", 1u << level)
        .set("FEEDBACK", i == tap)
        .set("BLOCK", kAtrousBlock)
        .set("CLASS_EDGES", last.motion == MotionSource::Reflection)
        .set("KERNEL_RADIUS", v.kernel == AtrousKernel::B3_5x5 ? 2u : 1u)
        .set("LUMINANCE_VARIANCE", v.luminance_weight == LuminanceWeight::Variance)
        .set("AGE_GATED_LUMINANCE", v.young_variance == YoungVariance::LuminanceOff)
        .set("DISPLAY_FILL", v.validity_mask.has_value() && i + 1 == v.iterations)
        .set("SIGNALS", static_cast<uint32_t>(v.signals.size()))
        .set("NORMAL_POWER", static_cast<uint32_t>(v.normal_power))
        .set("LUMINANCE_RAMP", v.luminance_ramp);
    if (i == tap) atrous.bind("colour_history", v.signals[0].history + "_colour");
    if (two) {
      atrous.bind("src2", buffers[1].illum).bind("dst2", buffers[1].other);
      if (i == tap) atrous.bind("colour_history2", v.signals[1].history + "_colour");
      bind_second_geometry(atrous, buffers[0], buffers[1]);
    }
    if (i == tap && v.validity_mask) bind_validity_mask(atrous);
    if (!last.spatial_bandwidth.empty()) atrous.bind("bandwidth", last.spatial_bandwidth).set("SPATIAL_BANDWIDTH", 1u);
    // Grid of server/pipelines/stages/svgf_atrous.comp: (ceil(W / span) * step) x (ceil(H / span) * step), span = step * block.
    const uint64_t step = uint64_t{1} << level, span = step * kAtrousBlock;
    atrous.invocations = ((config.width + span - 1) / span * step) * ((config.height + span - 1) / span * step);
    for (SignalBuffers& b : buffers) std::swap(b.illum, b.other);
    if (i == 0 && v.harm_guard)
      for (size_t s = 0; s < buffers.size(); ++s) buffers[s].other = s == 0 ? kIllumE : kIllumF;
  }
  std::vector<std::string> results;
  for (const SignalBuffers& b : buffers) results.push_back(b.illum);
  return results;
}

}  // namespace dn::pipelines::svgf
