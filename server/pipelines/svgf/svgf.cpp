// svgf: spatiotemporal variance-guided filtering (Schied et al. 2017) with
// Falcor's defaults (shaders/svgf_*.comp, docs/pipelines.md "svgf in detail"),
// as a variant description for the SVGF chain builder (svgf_chain.hpp):
// radiance mode (one signal, demodulated by albedo, emission subtracted when
// declared) or split mode (diffuse + specular, each in radiance or lighting
// form, split_signals.hpp: diffuse by albedo, specular by specular_albedo
// when declared, else filtered as sent; pass names suffixed _diffuse /
// _specular).
#include <optional>

#include "pipelines/definitions.hpp"
#include "pipelines/stages/split_signals.hpp"
#include "pipelines/stages/supersample.hpp"
#include "pipelines/stages/svgf_chain.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

SvgfVariant variant(const SessionConfig& config, const Parameters& p) {
  SvgfVariant v = svgf_variant_from(config, p);
  v.signals = radiance_or_split_signals(config, v.emission);
  return v;
}

GraphSpec build(const SessionConfig& config) { return svgf_graph(config, variant); }

std::optional<ConfigError> check_channels(const SessionConfig& config) {
  return check_split_channels(config, "svgf", /*radiance_allowed=*/true);
}

}  // namespace

PipelineDefinition svgf_definition() {
  PipelineDefinition d;
  d.description.name = "svgf";
  d.description.summary =
      "Spatiotemporal variance-guided filtering (Schied 2017, Falcor defaults): albedo demodulation, temporal "
      "integration of colour and luminance moments, variance-guided a-trous wavelet filter; Emission is added back "
      "unfiltered.";
  // Radiance, or the split pair in either form (check_channels): all optional in the masks.
  d.description.required_channels = protocol::channel_bit(ChannelId::Albedo) |
                                     protocol::channel_bit(ChannelId::Normal) |
                                     protocol::channel_bit(ChannelId::Depth) | protocol::channel_bit(ChannelId::Motion);
  d.description.optional_channels = protocol::channel_bit(ChannelId::Radiance) | split_channel_bits() |
                                     protocol::channel_bit(ChannelId::Emission) |
                                     protocol::channel_bit(ChannelId::Roughness) | extra_sample_channel_bits();
  d.parameter_groups = {"svgf"};
  d.description.parameters = parameters_of(d.parameter_groups);
  d.build = build;
  d.check_channels = check_channels;
  return d;
}

}  // namespace dn::pipelines
