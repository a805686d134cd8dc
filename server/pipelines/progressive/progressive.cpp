// progressive: progressive SVGF (Dundr 2018, paper 004; docs/pipelines.md
// "progressive") as a variant of the SVGF chain (svgf_chain.hpp): svgf's
// signals and passes with paper 004's constants (parameter_defaults), its
// 3x3 a-trous kernel, its luminance weight (a parameter) and, with a
// sample_count plane, its regime below one sample per pixel: unsampled
// pixels keep their history, pixels without data take no part, young pixels
// have no luminance weight instead of SVGF's spatial variance estimate, the
// steps go finest first and the display lags across the switch. Without the
// plane (a sample everywhere) the chain keeps SVGF's estimate and order.
#include <optional>
#include <string>

#include "pipelines/definitions.hpp"
#include "pipelines/progressive/gbuffer_fill.hpp"
#include "pipelines/stages/split_signals.hpp"
#include "pipelines/stages/supersample.hpp"
#include "pipelines/stages/svgf_chain.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

SvgfVariant variant(const SessionConfig& config, const Parameters& p) {
  SvgfVariant v = svgf_variant_from(config, p);
  v.signals = radiance_or_split_signals(config, v.emission);
  for (SvgfSignal& s : v.signals) s.clip = false;  // paper 004 clips nothing (check_channels)
  v.kernel = AtrousKernel::Box3x3;
  // Paper 004's young pixels have no usable variance below one sample per
  // pixel; a session without sample_count has a sample at every pixel every
  // frame, and SVGF's 7x7 spatial estimate stands in for it (no luminance
  // switch at coming of age, so no display lag across one).
  const bool sparse = has_channel(config, ChannelId::SampleCount);
  v.steps = p.progressive_step_order == 0.0f ? StepOrder::FinestFirst : StepOrder::Increasing;
  v.luminance_weight = p.progressive_luminance_form == 0.0f ? LuminanceWeight::VarianceGuided : LuminanceWeight::Variance;
  v.young_variance = sparse ? YoungVariance::LuminanceOff : YoungVariance::SpatialEstimate;
  if (sparse) v.validity_mask = ChannelId::SampleCount;
  v.display_lag = sparse && v.taa && p.progressive_display_lag != 0.0f;
  return v;
}

// svgf's graph; with sparse_gbuffer (check_channels: only with sample_count)
// the chain reads the depth and normal gbuffer_fill fills first.
GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  SvgfVariant v = variant(config, g.parameters);
  add_svgf_inputs(g, config, v);
  add_svgf_buffers(g, v);
  g.add_output(config);
  if (g.parameters.progressive_sparse_gbuffer != 0.0f) v.primary_features = add_gbuffer_fill(g, config);
  add_svgf_passes(g, config, v);
  return g;
}

std::optional<ConfigError> check_channels(const SessionConfig& config) {
  // svgf's history clipping reads every neighbour's current sample, which
  // fewer than one sample per pixel does not have: refused, not ignored.
  for (size_t i = 0; i < config.parameters.size(); ++i) {
    const ParameterValue& p = config.parameters[i];
    const std::string field = "parameters[" + std::to_string(i) + "].value";
    if (p.name == "clip_roughness" && p.value != 0.0)
      return ConfigError{ConfigProblem::InvalidParameter, field,
                         "progressive does not clip histories: clip_roughness must be 0"};
    // Which pixels lack a G-buffer is what sample_count says.
    if (p.name == "sparse_gbuffer" && p.value != 0.0 && !has_channel(config, ChannelId::SampleCount))
      return ConfigError{ConfigProblem::InvalidParameter, field,
                         "sparse_gbuffer needs the sample_count channel (which pixels have a G-buffer)"};
  }
  return check_split_channels(config, "progressive", /*radiance_allowed=*/true);
}

}  // namespace

PipelineDefinition progressive_definition() {
  PipelineDefinition d;
  d.description.name = "progressive";
  d.description.summary =
      "Progressive SVGF (Dundr 2018): the svgf chain with a 3x3 a-trous kernel, blend max(0.1, 1/age) and a final "
      "clamped TAA blend; with sample_count, fewer than one sample per pixel (unsampled pixels keep their history, "
      "young pixels have no luminance weight, steps 1, 16, 8, 4, 2).";
  // svgf's channels, without roughness (nothing is clipped) and the extra
  // samples (not combined with a validity mask), plus the mask.
  const PipelineDescription svgf = svgf_definition().description;
  d.description.required_channels = svgf.required_channels;
  d.description.optional_channels =
      (svgf.optional_channels & ~(protocol::channel_bit(ChannelId::Roughness) | extra_sample_channel_bits())) |
      protocol::channel_bit(ChannelId::SampleCount);
  d.parameter_groups = {"svgf", "atrous", "progressive"};
  // Paper 004's constants (§4.2-4.5): a = 0.1 for colour and moments, 5
  // a-trous passes, sigma_N 64, the final blend's fixed ratio 0.1; no clipping.
  d.parameter_defaults = {{"alpha_colour", 0.1},     {"alpha_moments", 0.1}, {"atrous_iterations", 5},
                          {"phi_normal", 64},        {"taa_alpha", 0.1},     {"taa_static_alpha", 0.1},
                          {"clip_roughness", 0}};
  d.description.parameters = parameters_of(d.parameter_groups, d.parameter_defaults);
  d.build = build;
  d.check_channels = check_channels;
  return d;
}

}  // namespace dn::pipelines
