#include "pipelines/stages/svgf_stages.hpp"

namespace dn::pipelines::svgf {

void add_reprojection(GraphSpec& g, const ReprojectStage& stage) {
  const SignalChain& s = stage.signal;
  PassSpec& reproject = g.add_pass("svgf_reproject" + s.suffix, "svgf_reproject");
  reproject.bind("signal", s.signal)
      .bind("normal", s.normal)
      .bind("depth", s.depth)
      .bind("motion", s.motion)
      .bind("prev_colour", s.colour_history)
      .bind("prev_aux", s.aux_history)
      .bind("illum", s.illum)
      .bind("guide", s.guide)
      .bind("temporal", s.temporal)
      .set("DEMODULATE", s.demodulates())
      .set("WRITE_GUIDE", stage.write_guide)
      .set("SUBTRACT_EMISSION", !s.emission.empty())
      .set("READ_HISTORY", stage.read_history)
      .set("SPECULAR_ALPHA", stage.specular_alpha);
  if (s.demodulates()) reproject.bind("modulator", s.modulator);
  if (!s.still_mean.empty())
    reproject.bind("still_mean", s.still_mean)
        .bind("still_m2", s.still_m2)
        .bind("still_change", s.still_change)
        .set("CONVERGE_STILL", 1u);
  if (!stage.surface_still.empty()) reproject.bind("surface_still", stage.surface_still).set("SURFACE_STILL", 1u);
  if (!s.emission.empty()) reproject.bind("emission", s.emission);
  if (stage.clip)
    reproject.bind("neighbourhood", stage.clip->neighbourhood)
        .bind("current", stage.clip->current)
        .bind("roughness", stage.clip->roughness)
        .set("CLIP", 1u);
  if (!s.reflection_motion.empty()) reproject.bind("reflection", s.reflection_motion).set("REFLECTION", 1u);
  if (!stage.validity_mask.empty()) bind_validity_mask(reproject, stage.validity_mask);
  reproject.pixels_per_invocation = 1;
}

}  // namespace dn::pipelines::svgf
