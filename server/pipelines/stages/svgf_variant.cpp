#include "pipelines/stages/svgf_chain.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "pipelines/stages/supersample.hpp"

namespace dn::pipelines {

using protocol::ChannelId;

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

}  // namespace dn::pipelines
