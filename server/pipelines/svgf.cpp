// svgf: spatiotemporal variance-guided filtering (Schied et al. 2017) with
// Falcor's defaults (shaders/svgf_*.comp, docs/pipelines.md "svgf in detail").
// Passes: svgf_reproject, svgf_variance, svgf_atrous_<i> for i < atrous_iterations
// (step 2^i as specialization constant 3: one pipeline per iteration),
// svgf_remodulate.
#include <algorithm>
#include <string>

#include "pipelines/definitions.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

// Per pixel, a single persistent copy (svgf_reproject reads it; svgf_variance
// and the feedback a-trous iteration rewrite it after that pass):
// vec4(demodulated rgb, length) fp32 and uvec4(m1, m2, depth as fp32 bits,
// octahedral snorm16x2 normal).
constexpr uint64_t kColourHistoryBytes = 16;
constexpr uint64_t kAuxHistoryBytes = 16;
// Scratch, per pixel: vec4(demodulated rgb, variance) fp32, two for the a-trous ping-pong.
constexpr uint64_t kIlluminationBytes = 16;
// Scratch, per pixel: guide uvec4(signed depth, packed normal, dz, 0) and
// temporal vec4(m1, m2, length, luminance), written by svgf_reproject.
constexpr uint64_t kGuideBytes = 16;
constexpr uint64_t kTemporalBytes = 16;
// a-trous register block: one invocation filters kAtrousBlock^2 pixels.
constexpr uint32_t kAtrousBlock = 4;
// svgf_variance register block: kVarianceBlock^2 pixels per invocation.
constexpr uint32_t kVarianceBlock = 2;

// Slots of parameters.def (svgf rows).
constexpr uint32_t kIterationsSlot = 3;
constexpr uint32_t kFeedbackSlot = 4;

bool has_channel(const SessionConfig& config, ChannelId id) {
  for (const auto& c : config.channels)
    if (c.id == id) return true;
  return false;
}

GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  const bool emission = has_channel(config, ChannelId::Emission);
  g.add_input(config, ChannelId::Radiance, "radiance");
  g.add_input(config, ChannelId::Albedo, "albedo");
  g.add_input(config, ChannelId::Normal, "normal");
  g.add_input(config, ChannelId::Depth, "depth");
  g.add_input(config, ChannelId::Motion, "motion");
  if (emission) g.add_input(config, ChannelId::Emission, "emission");
  g.add_persistent("svgf_colour", kColourHistoryBytes);
  g.add_persistent("svgf_aux", kAuxHistoryBytes);
  const uint32_t iterations = static_cast<uint32_t>(g.parameters[kIterationsSlot]);
  const uint32_t tap = std::min(static_cast<uint32_t>(g.parameters[kFeedbackSlot]), iterations ? iterations - 1 : 0u);
  const uint64_t pixels = uint64_t{config.width} * config.height;
  for (auto [name, bytes] : {std::pair{"svgf_illum_a", kIlluminationBytes}, std::pair{"svgf_illum_b", kIlluminationBytes},
                              std::pair{"svgf_guide", kGuideBytes}, std::pair{"svgf_temporal", kTemporalBytes}}) {
    if (iterations == 0 && std::string(name) == "svgf_illum_b") continue;
    BufferSpec b;
    b.name = name;
    b.role = BufferRole::Scratch;
    b.bytes = round_up4(pixels * bytes);
    g.buffers.push_back(std::move(b));
  }
  g.add_output(config);

  const uint32_t radiance_half = is_half(channel_format(config, ChannelId::Radiance));
  const uint32_t albedo_half = is_half(channel_format(config, ChannelId::Albedo));
  const uint32_t normal_half = is_half(channel_format(config, ChannelId::Normal));
  const uint32_t depth_half = is_half(channel_format(config, ChannelId::Depth));
  const uint32_t motion_half = is_half(channel_format(config, ChannelId::Motion));

  PassSpec reproject;
  reproject.name = reproject.shader = "svgf_reproject";
  reproject.bindings = {{"radiance"},
                        {"albedo"},
                        {"normal"},
                        {"depth"},
                        {"motion"},
                        {"svgf_colour"},
                        {"svgf_aux"},
                        {"svgf_illum_a"},
                        {"svgf_guide"},
                        {"svgf_temporal"}};
  reproject.spec_constants = {{1, radiance_half}, {2, albedo_half}, {3, normal_half}, {4, depth_half}, {5, motion_half}};
  reproject.pixels_per_invocation = 1;
  g.passes.push_back(std::move(reproject));

  PassSpec variance;
  variance.name = variance.shader = "svgf_variance";
  variance.bindings = {{"svgf_guide"}, {"svgf_temporal"}, {"svgf_illum_a"}, {"svgf_colour"}, {"svgf_aux"}};
  variance.spec_constants = {{1, kVarianceBlock}};
  variance.invocations = uint64_t{(config.width + kVarianceBlock - 1) / kVarianceBlock} *
                         ((config.height + kVarianceBlock - 1) / kVarianceBlock);
  g.passes.push_back(std::move(variance));

  std::string current = "svgf_illum_a", other = "svgf_illum_b";
  for (uint32_t i = 0; i < iterations; ++i) {
    PassSpec atrous;
    atrous.name = "svgf_atrous_" + std::to_string(i);
    atrous.shader = "svgf_atrous";
    atrous.bindings = {{"svgf_guide"}, {current}, {other}, {"svgf_colour"}};
    atrous.spec_constants = {{3, 1u << i}, {4, i == tap ? 1u : 0u}, {5, kAtrousBlock}};
    // Grid of shaders/svgf_atrous.comp: (ceil(W / span) * step) x (ceil(H / span) * step), span = step * block.
    const uint64_t step = uint64_t{1} << i, span = step * kAtrousBlock;
    atrous.invocations = ((config.width + span - 1) / span * step) * ((config.height + span - 1) / span * step);
    g.passes.push_back(std::move(atrous));
    std::swap(current, other);
  }

  PassSpec remodulate;
  remodulate.name = remodulate.shader = "svgf_remodulate";
  remodulate.bindings = {{current}, {"albedo"}, {emission ? "emission" : "albedo"}, {"output"}};
  remodulate.spec_constants = {{1, albedo_half},
                               {2, emission ? is_half(channel_format(config, ChannelId::Emission)) : 0u},
                               {3, emission ? 1u : 0u},
                               {4, is_half(config.output_format)}};
  g.passes.push_back(std::move(remodulate));
  return g;
}

}  // namespace

PipelineDefinition svgf_definition() {
  PipelineDefinition d;
  d.description.name = "svgf";
  d.description.summary =
      "Spatiotemporal variance-guided filtering (Schied 2017, Falcor defaults): albedo demodulation, temporal "
      "integration of colour and luminance moments, variance-guided a-trous wavelet filter; Emission is added back "
      "unfiltered.";
  d.description.required_channels =
      protocol::channel_bit(ChannelId::Radiance) | protocol::channel_bit(ChannelId::Albedo) |
      protocol::channel_bit(ChannelId::Normal) | protocol::channel_bit(ChannelId::Depth) |
      protocol::channel_bit(ChannelId::Motion);
  d.description.optional_channels = protocol::channel_bit(ChannelId::Emission);
  d.description.parameters = parameters_of("svgf");
  d.build = build;
  return d;
}

}  // namespace dn::pipelines
