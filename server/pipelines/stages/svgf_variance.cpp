#include "pipelines/stages/svgf_stages.hpp"

namespace dn::pipelines::svgf {

// One pass for every signal (the joint chain: the guide's loads and the 7x7
// estimate's geometric weights shared), which also writes each signal's
// history for the next frame.
void add_variance(GraphSpec& g, const VarianceStage& stage) {
  const SignalChain& first = stage.signals[0];
  PassSpec& variance = g.add_pass("svgf_variance", "svgf_variance");
  variance.bind("guide", first.guide)
      .bind("temporal", first.temporal)
      .bind("illum", first.illum)
      .bind("colour_history", first.colour_history)
      .bind("aux_history", first.aux_history)
      .set("SPATIAL_ESTIMATE", stage.spatial_estimate)
      .set("SIGNALS", static_cast<uint32_t>(stage.signals.size()));
  variance.pixels_per_invocation = 1;
  if (stage.signals.size() > 1) {
    const SignalChain& second = stage.signals[1];
    variance.bind("illum2", second.illum)
        .bind("colour_history2", second.colour_history)
        .bind("aux_history2", second.aux_history);
    bind_second_geometry(variance, first, second);
  }
}

}  // namespace dn::pipelines::svgf
