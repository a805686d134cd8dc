#include "pipelines/stages/svgf_chain.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "pipelines/definitions.hpp"
#include "pipelines/sample_summary.hpp"
#include "pipelines/stages/supersample.hpp"
#include "pipelines/stages/svgf_buffers.hpp"
#include "pipelines/stages/svgf_stages.hpp"

namespace dn::pipelines {

using protocol::ChannelId;
using namespace svgf;

int32_t normal_power_of(float phi_normal) {
  for (int32_t k = 0; k <= kMaxNormalPower; ++k)
    if (phi_normal == static_cast<float>(1u << k)) return k;
  return -1;
}

uint32_t step_level(StepOrder order, uint32_t i, uint32_t n) {
  switch (order) {
    case StepOrder::Increasing: return i;
    case StepOrder::Decreasing: return n - 1 - i;
    case StepOrder::FinestFirst: return i == 0 ? 0 : n - i;
  }
  return i;
}

SvgfVariant svgf_variant_from(const SessionConfig& config, const Parameters& p) {
  SvgfVariant v;
  v.iterations = static_cast<uint32_t>(p.svgf_atrous_iterations);
  v.feedback_tap = static_cast<uint32_t>(p.svgf_feedback_tap);
  v.taa = p.svgf_taa_alpha > 0.0f || p.svgf_taa_static_alpha > 0.0f;
  v.emission = has_channel(config, protocol::ChannelId::Emission);
  // Clipping needs to know the glossy pixels: without a roughness plane it
  // would clip diffuse noise too (and bias sparse samples toward black).
  v.roughness = has_channel(config, protocol::ChannelId::Roughness);
  v.clip = p.svgf_clip_roughness > 0.0f && v.roughness;
  v.extra_samples = extra_samples(config);
  v.normal_power = normal_power_of(p.svgf_phi_normal);
  v.luminance_ramp = p.svgf_luminance_ramp != 0.0f;
  v.harm_guard = p.svgf_harm_guard > 0.0f;
  v.keep_unexplained = p.svgf_keep_unexplained != 0.0f;
  v.converge_still = p.svgf_converge_still != 0.0f;
  return v;
}

void check_supported(const SvgfVariant& v) {
  auto reject = [](const std::string& what) { throw std::logic_error("svgf variant: " + what); };
  if (v.signals.empty() || v.signals.size() > 2)
    reject("svgf_remodulate combines one or two signals, not " + std::to_string(v.signals.size()));
  if (v.signals[0].modulator.empty())
    reject("the first signal needs a modulator: svgf_remodulate multiplies it by one");
  for (size_t i = 0; i + 1 < v.signals.size(); ++i)
    if (v.signals[i].motion == MotionSource::Reflection || !v.signals[i].spatial_bandwidth.empty() ||
        v.signals[i].specular_alpha)
      reject("signal " + v.signals[i].input + ": reflection motion, a spatial bandwidth and the specular alpha are "
             "the last signal's only (the joint variance and a-trous passes apply them to it)");
  for (const SvgfSignal& s : v.signals) {
    if (s.input.empty() || s.history.empty()) reject("a signal needs an input plane and a history name");
    if (s.motion == MotionSource::Reflection && s.reflection_motion.empty())
      reject("signal " + s.input + " takes reflection motion but names no reflect_motion buffer");
    if (s.features && (s.features->depth.empty() || s.features->normal.empty()))
      reject("signal " + s.input + ": its own features need a depth and a normal buffer");
  }
  if (v.validity_mask && *v.validity_mask != ChannelId::SampleCount)
    reject("validity mask: only the sample_count plane is one");
  if (v.primary_features && (v.primary_features->depth.empty() || v.primary_features->normal.empty()))
    reject("primary features need a depth and a normal buffer");
  if (v.display_lag && !v.taa) reject("display_lag lags the final blend: it needs taa");
  if (v.validity_mask && std::any_of(v.signals.begin(), v.signals.end(), [](const SvgfSignal& s) { return s.clip; }))
    reject("validity mask with a clipped signal: the clip box reads every neighbour's current sample");
  if (v.iterations > 16) reject("more than 16 a-trous iterations (step 2^16)");
}

void add_svgf_inputs(GraphSpec& g, const SessionConfig& config, const SvgfVariant& v) {
  for (const SvgfSignal& s : v.signals) g.add_input(config, s.channel, s.input);
  for (const SvgfSignal& s : v.signals)
    if (s.modulator.plane && !g.find(s.modulator.buffer)) g.add_input(config, *s.modulator.plane, s.modulator.buffer);
  g.add_input(config, ChannelId::Normal, "normal");
  g.add_input(config, ChannelId::Depth, "depth");
  g.add_input(config, ChannelId::Motion, "motion");
  if (v.emission) g.add_input(config, ChannelId::Emission, "emission");
  if (v.validity_mask) g.add_input(config, *v.validity_mask, "sample_count");
  if (v.roughness && !g.find("roughness")) g.add_input(config, ChannelId::Roughness, "roughness");
  if (v.extra_samples) {
    std::vector<ChannelId> channels;
    for (const SvgfSignal& s : v.signals) channels.push_back(s.channel);
    add_supersample_inputs(g, config, channels);
  }
}

void add_svgf_buffers(GraphSpec& g, const SvgfVariant& v) {
  for (const SvgfSignal& s : v.signals) {
    g.add_persistent(s.history + "_colour");
    g.add_persistent(s.history + "_aux");
    if (keeps_still_mean(v)) {
      g.add_persistent(still_mean_of(s.history));
      g.add_persistent(still_m2_of(s.history));
      g.add_persistent(still_change_of(s.history));
    }
  }
  if (keeps_still_emission(v)) {
    g.add_persistent(kEmissionStill);
    g.add_persistent(kEmissionTest);
  }
  if (v.taa) g.add_persistent(kTaaHistory);
  if (!v.display.empty()) g.add_scratch(v.display);
  if (v.extra_samples) {
    std::vector<std::string> inputs;
    for (const SvgfSignal& s : v.signals) inputs.push_back(s.input);
    add_supersample_buffers(g, inputs);
    g.add_scratch(kSupersampleDisplay);
  }
  const bool third = v.harm_guard && v.iterations > 1;  // the guard's own ping-pong partner
  g.add_scratch(kIllumA);
  if (v.iterations > 0) g.add_scratch(kIllumB);
  if (third) g.add_scratch(kIllumE);
  if (v.signals.size() > 1) {
    g.add_scratch(kIllumC);
    if (v.iterations > 0) g.add_scratch(kIllumD);
    if (third) g.add_scratch(kIllumF);
  }
  // One guide and temporal per signal (the joint a-trous passes read both),
  // except that a second signal without features of its own shares the guide.
  for (size_t i = 0; i < v.signals.size(); ++i) {
    const SignalBuffers b = signal_buffers(v, i);
    if (i == 0 || b.guide != kGuide) g.add_scratch(b.guide);
    g.add_scratch(b.temporal);
  }
  const bool clips = v.clip && std::any_of(v.signals.begin(), v.signals.end(), [](const SvgfSignal& s) { return s.clip; });
  if (clips) {
    g.add_scratch(kClipCurrent);
    g.add_scratch(kClipPartial);
    g.add_scratch(kClipNeighbourhood);
  }
}

void add_svgf_passes(GraphSpec& g, const SessionConfig& config, const SvgfVariant& v) {
  check_supported(v);
  if (v.extra_samples) {
    add_supersample_assign(g, config);
    for (const SvgfSignal& s : v.signals) add_supersample_mix(g, config, s.channel, s.input, s.suffix);
  }
  for (size_t i = 0; i < v.signals.size(); ++i) add_reprojection(g, v, i);
  add_variance(g, v);
  const std::vector<std::string> results = add_atrous(g, config, v);
  add_remodulate(g, v, results);
  if (v.extra_samples && v.display.empty()) add_supersample_resolve(g, config, kSupersampleDisplay);
  // RESULT.samples: the first chain's history length, or its still mean's count.
  add_sample_summary(g, v.signals[0].history + "_colour", still_mean_buffer(v));
}

std::string still_mean_buffer(const SvgfVariant& v) { return keeps_still_mean(v) ? still_mean_of(v.signals[0].history) : ""; }
std::string still_m2_buffer(const SvgfVariant& v) { return keeps_still_mean(v) ? still_m2_of(v.signals[0].history) : ""; }

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
