#include "pipelines/stages/svgf_stages.hpp"

#include "pipelines/stages/supersample.hpp"
#include "pipelines/stages/svgf_buffers.hpp"

namespace dn::pipelines::svgf {

using protocol::ChannelId;

void add_remodulate(GraphSpec& g, const SvgfVariant& v, const std::vector<std::string>& results) {
  // With TAA, svgf_remodulate writes the current colour and the reprojected
  // TAA history instead of Output, and svgf_taa blends them: into the
  // temporal and the guide scratch, whose contents are dead once the a-trous
  // chains are done. Without it, the TAA bindings stay unbound.
  if (v.taa) {
    g.add_alias(kTaaCurrent, kTemporal);
    g.add_alias(kTaaPrevious, kGuide);
  }
  const Modulator& first = v.signals[0].modulator;
  // Output, or a scratch frame for the resolve.
  const std::string result = v.extra_samples ? kSupersampleDisplay : "output";
  // The last pass's frame: Output (or the resolve's), or the caller's display.
  auto bind_result = [&](PassSpec& pass) {
    if (v.display.empty()) pass.bind("result", result);
    else pass.bind("display", v.display).set("TO_DISPLAY", 1u);
  };
  PassSpec& remodulate = g.add_pass("svgf_remodulate", "svgf_remodulate");
  remodulate.bind("illum", results[0])
      .bind("albedo", first.buffer)
      .set("HAS_EMISSION", v.emission)
      .set("HAS_SPECULAR", v.signals.size() > 1)
      .set("TAA", v.taa);
  if (!v.taa) bind_result(remodulate);
  if (v.emission)
    remodulate.bind("emission", "emission");
  if (keeps_still_emission(v))
    remodulate.bind("emission_still", kEmissionStill).bind("emission_test", kEmissionTest).set("EMISSION_STILL", 1u);
  if (v.signals.size() > 1) {
    remodulate.bind("specular", results[1]);
    const Modulator& second = v.signals[1].modulator;
    if (!second.empty())
      remodulate.bind("specular_factor", second.buffer)
          .set("SPECULAR_FACTOR", 1u);
  }
  // keep: the (diffuse) albedo must be a client plane, the test's input; with
  // a validity mask only sampled pixels have a current radiance to keep.
  const bool radiance = v.signals.size() == 1 && v.signals[0].channel == ChannelId::Radiance;
  const bool keep = v.keep_unexplained && (radiance || v.signals.size() == 2) && !v.extra_samples &&
                    first.plane == ChannelId::Albedo;
  // Motion: the TAA reprojection's, a still unexplained pixel's history (with the guard's buffer), still emission.
  if (v.taa || keep || keeps_still_emission(v)) remodulate.bind("motion", "motion");
  // Depth: the TAA's foreground test, still emission's (a background pixel keeps no mean).
  if (v.taa || keeps_still_emission(v))
    remodulate.bind("depth", primary_depth(v));
  if (v.taa) remodulate.bind("taa_history", kTaaHistory).bind("taa_current", kTaaCurrent).bind("taa_previous", kTaaPrevious);
  const bool guard = v.harm_guard && v.iterations > 0;
  // The first chain's history (its length): read by the display lag and the harm guard.
  if (v.display_lag || guard) remodulate.bind("colour_history", v.signals[0].history + "_colour");
  if (v.display_lag) remodulate.set("DISPLAY_LAG", 1u);
  if (keep) {
    remodulate.bind("raw", v.signals[0].input)
        .set("KEEP_UNEXPLAINED", 1u)
        .set("RAW_DIVIDED", first.client_divided);
    if (v.validity_mask) bind_validity_mask(remodulate);
    if (v.signals.size() > 1)
      remodulate.bind("raw2", v.signals[1].input)
          .set("RAW2_DIVIDED", v.signals[1].modulator.client_divided);
  }
  if (guard) {
    remodulate.bind("own", signal_buffers(v, 0).illum).set("HARM_GUARD", 1u);
    if (v.signals.size() > 1)
      remodulate.bind("own2", signal_buffers(v, 1).illum).bind("colour_history2", v.signals[1].history + "_colour");
    if (keeps_still_mean(v)) {
      remodulate.bind("still_mean", still_mean_of(v.signals[0].history))
          .bind("still_m2", still_m2_of(v.signals[0].history))
          .set("CONVERGE_STILL", 1u);
      if (v.signals.size() > 1)
        remodulate.bind("still_mean2", still_mean_of(v.signals[1].history))
            .bind("still_m2_2", still_m2_of(v.signals[1].history))
            .set("SPECULAR_ALPHA", v.signals[1].specular_alpha);
    }
  }

  if (v.taa) {
    PassSpec& taa = g.add_pass("svgf_taa", "svgf_taa");
    taa.bind("current", kTaaCurrent).bind("previous", kTaaPrevious).bind("history", kTaaHistory)
        .bind("depth", primary_depth(v));
    bind_result(taa);
    if (v.display_lag) taa.set("DISPLAY_LAG", 1u);
  }
}

}  // namespace dn::pipelines::svgf
