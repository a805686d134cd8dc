#include "pipelines/stages/svgf_stages.hpp"

namespace dn::pipelines::svgf {

void add_remodulate(GraphSpec& g, const RemodulateStage& stage) {
  const SignalChain& first = stage.signals[0];
  const bool two = stage.signals.size() > 1;
  const bool keep = !stage.keep_raw.empty();
  const bool emission_still = !stage.emission_still.empty();
  PassSpec& remodulate = g.add_pass("svgf_remodulate", "svgf_remodulate");
  remodulate.bind("illum", stage.filtered[0])
      .bind("albedo", first.modulator)
      .set("HAS_EMISSION", !stage.emission.empty())
      .set("HAS_SPECULAR", two)
      .set("TAA", stage.taa.has_value());
  if (!stage.taa) bind_target(remodulate, stage.target);
  if (!stage.emission.empty()) remodulate.bind("emission", stage.emission);
  if (emission_still)
    remodulate.bind("emission_still", stage.emission_still)
        .bind("emission_test", stage.emission_test)
        .set("EMISSION_STILL", 1u);
  if (two) {
    remodulate.bind("specular", stage.filtered[1]);
    if (!stage.signals[1].modulator.empty())
      remodulate.bind("specular_factor", stage.signals[1].modulator).set("SPECULAR_FACTOR", 1u);
  }
  // Motion: the TAA's reprojection, a still kept pixel's history, still emission.
  if (stage.taa || keep || emission_still) remodulate.bind("motion", stage.motion);
  // Depth: the TAA's foreground test, still emission's (a background pixel keeps no mean).
  if (stage.taa || emission_still) remodulate.bind("depth", stage.depth);
  if (stage.taa)
    remodulate.bind("taa_history", stage.taa->history)
        .bind("taa_current", stage.taa->current)
        .bind("taa_previous", stage.taa->previous);
  // The first signal's history (its length): read by the display lag and the harm guard.
  if (stage.display_lag || stage.harm_guard) remodulate.bind("colour_history", first.colour_history);
  if (stage.display_lag) remodulate.set("DISPLAY_LAG", 1u);
  if (keep) {
    remodulate.bind("raw", stage.keep_raw[0]).set("KEEP_UNEXPLAINED", 1u).set("RAW_DIVIDED", first.client_divided);
    if (!stage.validity_mask.empty()) bind_validity_mask(remodulate, stage.validity_mask);
    if (two)
      remodulate.bind("raw2", stage.keep_raw[1]).set("RAW2_DIVIDED", stage.signals[1].client_divided);
  }
  if (stage.harm_guard) {
    remodulate.bind("own", first.illum).set("HARM_GUARD", 1u);
    if (two)
      remodulate.bind("own2", stage.signals[1].illum).bind("colour_history2", stage.signals[1].colour_history);
    if (!first.still_mean.empty()) {
      remodulate.bind("still_mean", first.still_mean).bind("still_m2", first.still_m2).set("CONVERGE_STILL", 1u);
      if (two)
        remodulate.bind("still_mean2", stage.signals[1].still_mean)
            .bind("still_m2_2", stage.signals[1].still_m2)
            .set("SPECULAR_ALPHA", stage.specular_alpha);
    }
  }
}

}  // namespace dn::pipelines::svgf
