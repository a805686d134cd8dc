#include "pipelines/stages/svgf_stages.hpp"

#include "pipelines/stages/svgf_buffers.hpp"

namespace dn::pipelines::svgf {

namespace {

// The passes of the separable 7x7 prefilter history clipping takes its box
// from: the demodulated current signal once per pixel, rows, columns.
void add_clip_prefilter(GraphSpec& g, const SvgfVariant& v, const SvgfSignal& s, bool demodulate) {
  PassSpec& current = g.add_pass("svgf_clip_current" + s.suffix, "svgf_clip_prefilter");
  current.bind("signal", signal_buffer(v, s))
      .bind("depth", "depth")
      .bind("dst", kClipCurrent)
      .mode("current")
      .set("DEMODULATE", demodulate)
      .set("SUBTRACT_EMISSION", s.subtract_emission);
  if (demodulate) current.bind("modulator", s.modulator.buffer);
  if (s.subtract_emission)
    current.bind("emission", "emission");
  current.pixels_per_invocation = 1;
  g.add_pass("svgf_clip_prefilter_x" + s.suffix, "svgf_clip_prefilter")
      .bind("src", kClipCurrent)
      .bind("dst", kClipPartial)
      .mode("horizontal")
      .pixels_per_invocation = 1;
  g.add_pass("svgf_clip_prefilter_y" + s.suffix, "svgf_clip_prefilter")
      .bind("src", kClipPartial)
      .bind("dst", kClipNeighbourhood)
      .mode("vertical")
      .pixels_per_invocation = 1;
}

}  // namespace

void add_reprojection(GraphSpec& g, const SvgfVariant& v, size_t index) {
  const SvgfSignal& s = v.signals[index];
  const SignalBuffers buffers = signal_buffers(v, index);
  const std::string colour = s.history + "_colour", aux = s.history + "_aux";
  const bool demodulate = !s.modulator.empty() && !s.modulator.client_divided;
  // Features: the signal's own, the filled sparse G-buffer or the primary planes.
  const std::string depth = s.features ? s.features->depth : primary_depth(v);
  const std::string normal = s.features ? s.features->normal : primary_normal(v);
  const bool clip = v.clip && s.clip;
  if (clip) add_clip_prefilter(g, v, s, demodulate);

  PassSpec& reproject = g.add_pass("svgf_reproject" + s.suffix, "svgf_reproject");
  reproject.bind("signal", signal_buffer(v, s))
      .bind("normal", normal)
      .bind("depth", depth)
      .bind("motion", "motion")
      .bind("prev_colour", colour)
      .bind("prev_aux", aux)
      .bind("illum", buffers.illum)
      .bind("guide", buffers.guide)
      .bind("temporal", buffers.temporal)
      .set("DEMODULATE", demodulate)
      .set("WRITE_GUIDE", index == 0 || s.features.has_value())  // else: the first signal's guide
      .set("SUBTRACT_EMISSION", s.subtract_emission)
      .set("READ_HISTORY", s.reads_history)
      .set("SPECULAR_ALPHA", s.specular_alpha);
  if (demodulate) reproject.bind("modulator", s.modulator.buffer);
  if (keeps_still_mean(v))
    reproject.bind("still_mean", still_mean_of(s.history))
        .bind("still_m2", still_m2_of(s.history))
        .bind("still_change", still_change_of(s.history))
        .set("CONVERGE_STILL", 1u);
  // A signal on the reflected hit's features keeps its still mean while the pixel's surface does.
  if (keeps_still_mean(v) && index > 0 && s.features)
    reproject.bind("surface_still", still_mean_of(v.signals[0].history)).set("SURFACE_STILL", 1u);
  if (s.subtract_emission)
    reproject.bind("emission", "emission");
  if (clip)
    reproject.bind("neighbourhood", kClipNeighbourhood)
        .bind("current", kClipCurrent)
        .bind("roughness", "roughness")
        .set("CLIP", 1u);
  if (s.motion == MotionSource::Reflection) reproject.bind("reflection", s.reflection_motion).set("REFLECTION", 1u);
  if (v.validity_mask) bind_validity_mask(reproject);
  reproject.pixels_per_invocation = 1;
}

}  // namespace dn::pipelines::svgf
