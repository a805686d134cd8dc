// accumulate: temporal accumulation with bilinear reprojection and
// depth/normal rejection (shaders/accumulate.comp, docs/pipelines.md).
#include "pipelines/definitions.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

// Per pixel, fp32: vec4(rgb, history length) and vec4(normal, depth).
constexpr uint64_t kColourHistoryBytes = 16;
constexpr uint64_t kGeometryHistoryBytes = 16;

GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  g.add_input(config, ChannelId::Radiance, "radiance");
  g.add_input(config, ChannelId::Normal, "normal");
  g.add_input(config, ChannelId::Depth, "depth");
  g.add_input(config, ChannelId::Motion, "motion");
  g.add_history("history_colour", kColourHistoryBytes);
  g.add_history("history_geometry", kGeometryHistoryBytes);
  g.add_output(config);

  PassSpec pass;
  pass.name = "accumulate";
  pass.shader = "accumulate";
  pass.bindings = {{"radiance"},
                   {"normal"},
                   {"depth"},
                   {"motion"},
                   {"history_colour", Slot::Previous},
                   {"history_geometry", Slot::Previous},
                   {"history_colour", Slot::Current},
                   {"history_geometry", Slot::Current},
                   {"output"}};
  pass.spec_constants = {{1, is_half(channel_format(config, ChannelId::Radiance))},
                         {2, is_half(channel_format(config, ChannelId::Normal))},
                         {3, is_half(channel_format(config, ChannelId::Depth))},
                         {4, is_half(channel_format(config, ChannelId::Motion))},
                         {5, is_half(config.output_format)}};
  g.passes.push_back(std::move(pass));
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
  d.description.parameters = parameters_of("accumulate");
  d.build = build;
  return d;
}

}  // namespace dn::pipelines
