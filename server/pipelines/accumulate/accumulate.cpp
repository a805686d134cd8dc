// accumulate: temporal accumulation with bilinear reprojection and
// depth/normal rejection (server/pipelines/accumulate/accumulate.comp, docs/pipelines.md).
#include "pipelines/definitions.hpp"
#include "pipelines/sample_summary.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  g.add_input(config, ChannelId::Radiance, "radiance");
  g.add_input(config, ChannelId::Normal, "normal");
  g.add_input(config, ChannelId::Depth, "depth");
  g.add_input(config, ChannelId::Motion, "motion");
  g.add_history("history_colour");
  g.add_history("history_geometry");
  g.add_output(config);

  g.add_pass("accumulate", "accumulate")
      .bind("radiance", "radiance")
      .bind("normal", "normal")
      .bind("depth", "depth")
      .bind("motion", "motion")
      .bind("prev_colour", "history_colour", Slot::Previous)
      .bind("prev_geometry", "history_geometry", Slot::Previous)
      .bind("cur_colour", "history_colour", Slot::Current)
      .bind("cur_geometry", "history_geometry", Slot::Current)
      .bind("result", GraphSpec::kOutput);
  add_sample_summary(g, "history_colour");
  return g;
}

}  // namespace

PipelineDefinition accumulate_definition() {
  PipelineDefinition d;
  d.description.name = "accumulate";
  d.description.summary =
      "Temporal accumulation of Radiance with bilinear reprojection along Motion and depth/normal rejection.";
  d.description.required_channels = protocol::channel_bit(ChannelId::Radiance) |
                                    protocol::channel_bit(ChannelId::Normal) |
                                    protocol::channel_bit(ChannelId::Depth) | protocol::channel_bit(ChannelId::Motion);
  d.parameter_groups = {"accumulate"};
  d.description.parameters = parameters_of(d.parameter_groups);
  d.build = build;
  return d;
}

}  // namespace dn::pipelines
