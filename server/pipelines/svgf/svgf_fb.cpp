// svgf-fb: svgf's split mode with the specular signal demodulated by the
// pre-integrated GGX F_beta instead of being filtered as sent (paper 000;
// docs/pipelines.md "svgf-fb"): one pass in front, svgf_fb_factor, computes
// F_beta = F0 * A + B per pixel from the context's F_beta table, and the SVGF
// chain (svgf_chain.hpp) runs with that factor as the specular modulator.
// Diffuse in either form (split_signals.hpp); specular as radiance only: the
// factor is this pipeline's point (a client with its own F_beta sends
// specular_lighting + specular_albedo to svgf instead).
#include "pipelines/definitions.hpp"
#include "pipelines/stages/fb_factor.hpp"
#include "pipelines/stages/split_signals.hpp"
#include "pipelines/stages/supersample.hpp"
#include "pipelines/stages/svgf_chain.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

// Scratch, per pixel: F_beta rgb fp32 (svgf_fb_factor).
constexpr const char* kFactor = "svgf_fb";

SvgfVariant variant(const SessionConfig& config, const Parameters& p) {
  SvgfVariant v = svgf_variant_from(config, p);
  v.signals = split_signals(config, Modulator{kFactor, std::nullopt});
  return v;
}

GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  const SvgfVariant v = variant(config, g.parameters);
  add_svgf_inputs(g, config, v);  // roughness included (history clipping reads it too)
  add_svgf_buffers(g, v);
  g.add_output(config);
  add_fb_factor(g, config, kFactor);
  add_svgf_passes(g, config, v);
  return g;
}

}  // namespace

PipelineDefinition svgf_fb_definition() {
  PipelineDefinition d;
  d.description.name = "svgf-fb";
  d.description.summary =
      "svgf on split lighting with BRDF pre-integration demodulation (paper 000): diffuse divided by albedo, "
      "specular by F_beta = F0 * A + B from a GGX table computed on the device at start-up; both filtered as "
      "svgf and remodulated. Diffuse may come as diffuse_lighting (already divided by albedo).";
  d.description.required_channels =
      protocol::channel_bit(ChannelId::Specular) | protocol::channel_bit(ChannelId::Albedo) | protocol::channel_bit(ChannelId::SpecularF0) |
      protocol::channel_bit(ChannelId::Roughness) | protocol::channel_bit(ChannelId::Normal) |
      protocol::channel_bit(ChannelId::Depth) | protocol::channel_bit(ChannelId::Motion);
  d.description.optional_channels = protocol::channel_bit(ChannelId::Diffuse) |
                                     protocol::channel_bit(ChannelId::DiffuseLighting) |
                                     protocol::channel_bit(ChannelId::Emission) | extra_sample_channel_bits();
  d.parameter_groups = {"svgf"};
  d.description.parameters = parameters_of(d.parameter_groups);
  d.shared_resources = {kFbLutResource};
  d.build = build;
  d.check_channels = check_split_only;
  return d;
}

}  // namespace dn::pipelines
