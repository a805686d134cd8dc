// The one place a variant becomes stages: each stage's struct from the
// variant and the resolved buffers (svgf_buffers.hpp), then the stages in order.
#include "pipelines/stages/svgf_chain.hpp"

#include <algorithm>
#include <string>
#include <vector>

#include "pipelines/definitions.hpp"
#include "pipelines/sample_summary.hpp"
#include "pipelines/stages/supersample.hpp"
#include "pipelines/stages/svgf_buffers.hpp"
#include "pipelines/stages/svgf_stages.hpp"

namespace dn::pipelines {

using protocol::ChannelId;
using namespace svgf;

namespace {

// Output, the resolve's frame with extra samples, or the caller's display.
FrameTarget frame_target(const SvgfVariant& v) {
  if (!v.display.empty()) return {v.display, true};
  return {v.extra_samples ? kSupersampleDisplay : GraphSpec::kOutput, false};
}

std::string validity_mask(const SvgfVariant& v) { return v.validity_mask ? kSampleCountPlane : ""; }

ClipStage clip_stage(const SignalChain& c) {
  // The foreground test reads the depth plane, whatever features the chain has.
  return {c.suffix, c.signal, kDepthPlane, c.demodulates() ? c.modulator : "", c.emission,
          kClipCurrent, kClipPartial, kClipNeighbourhood};
}

ReprojectStage reproject_stage(const SvgfVariant& v, const std::vector<SignalChain>& chains, size_t i) {
  const SvgfSignal& s = v.signals[i];
  ReprojectStage r;
  r.signal = chains[i];
  r.write_guide = i == 0 || s.features.has_value();
  r.read_history = s.reads_history;
  r.specular_alpha = s.specular_alpha;
  // A signal on the reflected hit's features keeps its still mean while the pixel's surface does.
  if (i > 0 && s.features) r.surface_still = chains[0].still_mean;
  if (clipped(v, s)) r.clip = ClipBox{kClipNeighbourhood, kClipCurrent, kRoughnessPlane};
  r.validity_mask = validity_mask(v);
  return r;
}

AtrousStage atrous_stage(const SvgfVariant& v, const std::vector<SignalChain>& chains) {
  AtrousStage a;
  a.signals = chains;
  for (uint32_t i = 0; i < v.iterations; ++i) a.levels.push_back(step_level(v.steps, i, v.iterations));
  a.feedback_tap = std::min(v.feedback_tap, v.iterations ? v.iterations - 1 : 0u);
  a.kernel_radius = v.kernel == AtrousKernel::B3_5x5 ? 2u : 1u;
  a.luminance_variance = v.luminance_weight == LuminanceWeight::Variance;
  a.age_gated_luminance = v.young_variance == YoungVariance::LuminanceOff;
  a.class_edges = v.signals.back().motion == MotionSource::Reflection;
  a.luminance_ramp = v.luminance_ramp;
  a.normal_power = v.normal_power;
  a.display_fill = v.validity_mask.has_value();
  a.bandwidth = v.signals.back().spatial_bandwidth;
  a.validity_mask = validity_mask(v);
  a.guard_partners = guard_partners(v);
  return a;
}

RemodulateStage remodulate_stage(const SvgfVariant& v, const std::vector<SignalChain>& chains,
                                 const std::vector<std::string>& filtered) {
  RemodulateStage r;
  r.signals = chains;
  r.filtered = filtered;
  if (v.emission) r.emission = kEmissionPlane;
  if (keeps_still_emission(v)) {
    r.emission_still = kEmissionStill;
    r.emission_test = kEmissionTest;
  }
  r.motion = kMotionPlane;
  r.depth = primary_depth(v);
  if (v.taa) r.taa = TaaBuffers{kTaaCurrent, kTaaPrevious, kTaaHistory};
  r.display_lag = v.display_lag;
  r.target = frame_target(v);
  // Keep: the (diffuse) albedo must be a client plane, the test's input; a
  // single signal must be radiance; with a validity mask only sampled pixels
  // have a current radiance to keep.
  const bool radiance = v.signals.size() == 1 && v.signals[0].channel == ChannelId::Radiance;
  if (v.keep_unexplained && (radiance || v.signals.size() == 2) && !v.extra_samples &&
      v.signals[0].modulator.plane == ChannelId::Albedo)
    for (const SvgfSignal& s : v.signals) r.keep_raw.push_back(s.input);
  r.validity_mask = validity_mask(v);
  r.harm_guard = v.harm_guard && v.iterations > 0;
  r.specular_alpha = v.signals.size() > 1 && v.signals[1].specular_alpha;
  return r;
}

}  // namespace

void add_svgf_passes(GraphSpec& g, const SessionConfig& config, const SvgfVariant& v) {
  check_supported(v);
  const std::vector<SignalChain> chains = signal_chains(v);
  if (v.extra_samples) {
    add_supersample_assign(g, config);
    for (const SvgfSignal& s : v.signals) add_supersample_mix(g, config, s.channel, s.input, s.suffix);
  }
  for (size_t i = 0; i < chains.size(); ++i) {
    if (clipped(v, v.signals[i])) add_clip_prefilter(g, clip_stage(chains[i]));
    add_reprojection(g, reproject_stage(v, chains, i));
  }
  add_variance(g, VarianceStage{chains, v.young_variance == YoungVariance::SpatialEstimate});
  const std::vector<std::string> filtered = add_atrous(g, config, atrous_stage(v, chains));
  const RemodulateStage remodulate = remodulate_stage(v, chains, filtered);
  add_remodulate(g, remodulate);
  if (remodulate.taa) add_taa(g, TaaStage{*remodulate.taa, remodulate.depth, v.display_lag, remodulate.target});
  if (v.extra_samples && v.display.empty()) add_supersample_resolve(g, config, kSupersampleDisplay);
  // RESULT.samples: the first chain's history length, or its still mean's count.
  add_sample_summary(g, chains[0].colour_history, chains[0].still_mean);
}

GraphSpec svgf_graph(const SessionConfig& config, SvgfVariant (*variant)(const SessionConfig&, const Parameters&)) {
  GraphSpec g = begin_graph(config);
  const SvgfVariant v = variant(config, g.parameters);
  add_svgf_inputs(g, config, v);
  add_svgf_buffers(g, v);
  g.add_output(config);
  add_svgf_passes(g, config, v);
  return g;
}

}  // namespace dn::pipelines
