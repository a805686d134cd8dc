#include "pipelines/stages/svgf_stages.hpp"

#include "pipelines/stages/svgf_buffers.hpp"

namespace dn::pipelines::svgf {

using protocol::ChannelId;

// One pass for every signal (the joint chain: the guide's loads and the 7x7
// estimate's geometric weights shared), which also writes each signal's
// history for the next frame.
void add_variance(GraphSpec& g, const SvgfVariant& v) {
  const SignalBuffers first = signal_buffers(v, 0);
  PassSpec& variance = g.add_pass("svgf_variance", "svgf_variance");
  variance.bind("guide", first.guide)
      .bind("temporal", first.temporal)
      .bind("illum", first.illum)
      .bind("colour_history", v.signals[0].history + "_colour")
      .bind("aux_history", v.signals[0].history + "_aux")
      .set("SPATIAL_ESTIMATE", v.young_variance == YoungVariance::SpatialEstimate)
      .set("SIGNALS", static_cast<uint32_t>(v.signals.size()));
  variance.pixels_per_invocation = 1;
  if (v.signals.size() > 1) {
    const SignalBuffers second = signal_buffers(v, 1);
    variance.bind("illum2", second.illum)
        .bind("colour_history2", v.signals[1].history + "_colour")
        .bind("aux_history2", v.signals[1].history + "_aux");
    bind_second_geometry(variance, first, second);
  }
}

}  // namespace dn::pipelines::svgf
