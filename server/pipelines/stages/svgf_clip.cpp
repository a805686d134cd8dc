#include "pipelines/stages/svgf_stages.hpp"

namespace dn::pipelines::svgf {

void add_clip_prefilter(GraphSpec& g, const ClipStage& stage) {
  const bool demodulate = !stage.modulator.empty();
  PassSpec& current = g.add_pass("svgf_clip_current" + stage.suffix, "svgf_clip_prefilter");
  current.bind("signal", stage.signal)
      .bind("depth", stage.depth)
      .bind("dst", stage.current)
      .mode("current")
      .set("DEMODULATE", demodulate)
      .set("SUBTRACT_EMISSION", !stage.emission.empty());
  if (demodulate) current.bind("modulator", stage.modulator);
  if (!stage.emission.empty()) current.bind("emission", stage.emission);
  current.pixels_per_invocation = 1;
  g.add_pass("svgf_clip_prefilter_x" + stage.suffix, "svgf_clip_prefilter")
      .bind("src", stage.current)
      .bind("dst", stage.partial)
      .mode("horizontal")
      .pixels_per_invocation = 1;
  g.add_pass("svgf_clip_prefilter_y" + stage.suffix, "svgf_clip_prefilter")
      .bind("src", stage.partial)
      .bind("dst", stage.neighbourhood)
      .mode("vertical")
      .pixels_per_invocation = 1;
}

}  // namespace dn::pipelines::svgf
