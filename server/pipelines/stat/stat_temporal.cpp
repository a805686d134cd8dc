// stat-temporal: stat over statistics accumulated across frames (paper 003
// §8's future work; docs/pipelines.md "stat-temporal"). stat_temporal
// reprojects each pixel's accumulator, tests it against the frame's
// statistics with the Welch test, merges what passes exactly (with a fading
// memory while the pixel moves) and starts afresh from the frame where it
// fails; stat_prepare and stat_filter then run on the accumulators.
#include "pipelines/sample_summary.hpp"
#include "pipelines/stat/stat_passes.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  // Without the renderer's statistics each frame's radiance is one sample.
  const bool from_radiance = !declares_statistics(config);
  add_stat_inputs(g, config, !from_radiance, g.parameters.stat_temporal_still_alpha);
  g.add_input(config, ChannelId::Depth, "depth");
  g.add_input(config, ChannelId::Motion, "motion");
  g.add_constant("stat_history_t_squared", t_squared_table(g.parameters.stat_temporal_history_alpha));
  g.add_history("stat_acc_count");
  for (const char* name : {"stat_acc_mean", "stat_acc_m2", "stat_acc_m3", "stat_acc_raw"})
    g.add_history(name);
  g.add_history("stat_acc_geometry");
  g.add_output(config);

  PassSpec& temporal = g.add_pass("stat_temporal", "stat_temporal")
      .bind("radiance", "radiance")
      .bind("depth", "depth")
      .bind("normal", "normal")
      .bind("motion", "motion")
      .bind("t_squared", "stat_history_t_squared")
      .bind("prev_count", "stat_acc_count", Slot::Previous)
      .bind("prev_mean", "stat_acc_mean", Slot::Previous)
      .bind("prev_m2", "stat_acc_m2", Slot::Previous)
      .bind("prev_m3", "stat_acc_m3", Slot::Previous)
      .bind("prev_raw", "stat_acc_raw", Slot::Previous)
      .bind("prev_geometry", "stat_acc_geometry", Slot::Previous)
      .bind("acc_count", "stat_acc_count")
      .bind("acc_mean", "stat_acc_mean")
      .bind("acc_m2", "stat_acc_m2")
      .bind("acc_m3", "stat_acc_m3")
      .bind("acc_raw", "stat_acc_raw")
      .bind("acc_geometry", "stat_acc_geometry")
      .set("TABLE_SIZE", kStatTableSize)
      .bind("albedo", "albedo");
  temporal.pixels_per_invocation = 1;
  if (from_radiance)
    temporal.set("FROM_RADIANCE", true);
  else
    temporal.bind("count", "stat_count").bind("mean", "stat_mean").bind("m2", "stat_m2").bind("m3", "stat_m3");
  if (g.parameters.stat_demodulated != 0.0f) {
    // The frame's own samples give the modulation; the accumulators cannot.
    g.add_scratch(kStatModulation);
    temporal.bind("modulation", kStatModulation).set("DEMODULATED", true);
  }
  StatSources accumulators{"stat_acc_count", "stat_acc_mean", "stat_acc_m2", "stat_acc_m3", "stat_acc_raw"};
  accumulators.prepare_modulates = false;  // stat_temporal wrote the modulation from the frame
  accumulators.classify = true;
  add_stat_filter(g, config, accumulators);
  // RESULT.samples: from the radiance alone a pixel's accumulated count is its frames (the renderer's counts are samples).
  if (from_radiance) add_sample_count_summary(g, "stat_acc_count");
  return g;
}

}  // namespace

PipelineDefinition stat_temporal_definition() {
  PipelineDefinition d;
  d.description.name = "stat-temporal";
  d.description.summary =
      "stat over sample statistics accumulated across frames: reprojected, tested against the frame with the same "
      "Welch test (a statistical disocclusion and ghosting test), merged exactly with a fading memory; works at 1 spp, "
      "and without the statistics planes from the radiance alone (one sample per pixel and frame).";
  d.description.required_channels = (stat_channels() & ~statistics_channels()) |
                                     protocol::channel_bit(ChannelId::Depth) | protocol::channel_bit(ChannelId::Motion);
  d.description.optional_channels = statistics_channels();
  d.parameter_groups = {"stat", "stat_temporal"};
  // A first frame from the radiance alone has no pixel with 2 samples: test each with its window's variance.
  // A still pixel's kernel narrows as its samples accumulate: its output tends to its own mean.
  d.parameter_defaults = {{"pool_single", 1}, {"spatial_shrink_from", 16}};
  d.description.parameters = parameters_of(d.parameter_groups, d.parameter_defaults);
  d.build = build;
  d.check_channels = check_optional_statistics;
  return d;
}

}  // namespace dn::pipelines
