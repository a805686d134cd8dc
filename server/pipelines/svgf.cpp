// svgf: spatiotemporal variance-guided filtering (Schied et al. 2017) with
// Falcor's defaults (shaders/svgf_*.comp, docs/pipelines.md "svgf in detail"),
// as a variant description for the SVGF chain builder (svgf_chain.hpp):
// radiance mode (one signal, demodulated by albedo, emission subtracted when
// declared) or split mode (Diffuse + Specular declared instead of Radiance:
// diffuse demodulated by albedo, specular filtered as sent; pass names
// suffixed _diffuse / _specular).
#include <algorithm>
#include <optional>
#include <string>

#include "pipelines/definitions.hpp"
#include "pipelines/svgf_chain.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

SvgfVariant variant(const SessionConfig& config, const Parameters& p) {
  SvgfVariant v = svgf_variant_from(config, p);
  const Modulator albedo{"albedo", ChannelId::Albedo};
  // validate() guarantees Diffuse and Specular together, without Radiance.
  if (has_channel(config, ChannelId::Diffuse)) {
    v.signals.push_back({ChannelId::Diffuse, "diffuse", "_diffuse", "svgf", albedo});
    v.signals.push_back({ChannelId::Specular, "specular", "_specular", "svgf_spec", Modulator{}});
  } else {
    // Radiance includes what the primary hit emits (docs/protocol.md); the
    // emitted part is added back unfiltered, so it is not filtered as well.
    SvgfSignal radiance{ChannelId::Radiance, "radiance", "", "svgf", albedo};
    radiance.subtract_emission = v.emission;
    v.signals.push_back(radiance);
  }
  return v;
}

GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  const SvgfVariant v = variant(config, g.parameters);
  add_svgf_inputs(g, config, v);
  add_svgf_buffers(g, v);
  g.add_output(config);
  add_svgf_passes(g, config, v);
  return g;
}

// The either/or rule of the lighting channels (validate() has checked each
// channel on its own and the required ones).
std::optional<ConfigError> check_channels(const SessionConfig& config) {
  using protocol::ErrorCode;
  int radiance = -1, diffuse = -1, specular = -1;
  for (size_t i = 0; i < config.channels.size(); ++i) {
    if (config.channels[i].id == ChannelId::Radiance) radiance = static_cast<int>(i);
    if (config.channels[i].id == ChannelId::Diffuse) diffuse = static_cast<int>(i);
    if (config.channels[i].id == ChannelId::Specular) specular = static_cast<int>(i);
  }
  if (radiance >= 0 && (diffuse >= 0 || specular >= 0)) {
    const int other = diffuse >= 0 ? diffuse : specular;
    return ConfigError{ErrorCode::InvalidChannel,
                       "OPEN_SESSION.channels[" + std::to_string(std::max(radiance, other)) + "].id",
                       "pipeline svgf takes either radiance or diffuse + specular, not both (radiance and " +
                           std::string(diffuse >= 0 ? "diffuse" : "specular") + " declared)"};
  }
  if (diffuse >= 0 && specular < 0)
    return ConfigError{ErrorCode::MissingChannel, "OPEN_SESSION.channels",
                       "pipeline svgf requires channel specular together with diffuse"};
  if (specular >= 0 && diffuse < 0)
    return ConfigError{ErrorCode::MissingChannel, "OPEN_SESSION.channels",
                       "pipeline svgf requires channel diffuse together with specular"};
  if (radiance < 0 && diffuse < 0)
    return ConfigError{ErrorCode::MissingChannel, "OPEN_SESSION.channels",
                       "pipeline svgf requires channel radiance, or diffuse and specular"};
  return std::nullopt;
}

}  // namespace

PipelineDefinition svgf_definition() {
  PipelineDefinition d;
  d.description.name = "svgf";
  d.description.summary =
      "Spatiotemporal variance-guided filtering (Schied 2017, Falcor defaults): albedo demodulation, temporal "
      "integration of colour and luminance moments, variance-guided a-trous wavelet filter; Emission is added back "
      "unfiltered.";
  // Radiance, or Diffuse + Specular (check_channels): both forms are optional in the masks.
  d.description.required_channels = protocol::channel_bit(ChannelId::Albedo) |
                                     protocol::channel_bit(ChannelId::Normal) |
                                     protocol::channel_bit(ChannelId::Depth) | protocol::channel_bit(ChannelId::Motion);
  d.description.optional_channels = protocol::channel_bit(ChannelId::Radiance) |
                                     protocol::channel_bit(ChannelId::Diffuse) |
                                     protocol::channel_bit(ChannelId::Specular) |
                                     protocol::channel_bit(ChannelId::Emission);
  d.parameter_groups = {"svgf"};
  d.description.parameters = parameters_of(d.parameter_groups);
  d.build = build;
  d.check_channels = check_channels;
  return d;
}

}  // namespace dn::pipelines
