// passthrough: Radiance -> Output, no filtering (non-finite values become 0).
// The honest baseline for transport benchmarks: it accepts every input channel
// and uploads each one declared, so a transport measurement pays the upload of
// a real pipeline's channel set.
#include "pipelines/definitions.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  g.add_input(config, ChannelId::Radiance, "radiance");
  for (const auto& decl : config.channels)
    if (decl.id != ChannelId::Radiance) g.add_input(config, decl.id, std::string(protocol::find_channel(decl.id)->name));
  g.add_output(config);
  g.add_pass("passthrough", "passthrough")
      .bind("radiance", "radiance")
      .bind("result", GraphSpec::kOutput);
  return g;
}

}  // namespace

PipelineDefinition passthrough_definition() {
  PipelineDefinition d;
  d.description.name = "passthrough";
  d.description.summary = "Copies Radiance to Output with format conversion only (no filtering).";
  d.description.required_channels = protocol::channel_bit(ChannelId::Radiance);
  for (const auto& c : protocol::kChannels)
    if (c.id != ChannelId::Radiance && c.id != ChannelId::Output) d.description.optional_channels |= protocol::channel_bit(c.id);
  d.description.parameters = parameters_of(d.parameter_groups);  // none
  d.build = build;
  return d;
}

}  // namespace dn::pipelines
