#include "pipelines/stages/svgf_buffers.hpp"

#include <algorithm>
#include <utility>

#include "pipelines/stages/supersample.hpp"

namespace dn::pipelines {

using protocol::ChannelId;

namespace svgf {

std::string primary_depth(const SvgfVariant& v) { return v.primary_features ? v.primary_features->depth : kDepthPlane; }

bool clipped(const SvgfVariant& v, const SvgfSignal& s) { return v.clip && s.clip; }
bool clips(const SvgfVariant& v) {
  return std::any_of(v.signals.begin(), v.signals.end(), [&](const SvgfSignal& s) { return clipped(v, s); });
}

bool keeps_still_mean(const SvgfVariant& v) { return v.converge_still && v.harm_guard && v.iterations > 0; }
bool keeps_still_emission(const SvgfVariant& v) { return v.emission && keeps_still_mean(v); }

std::vector<SignalChain> signal_chains(const SvgfVariant& v) {
  std::vector<SignalChain> chains;
  for (size_t i = 0; i < v.signals.size(); ++i) {
    const SvgfSignal& s = v.signals[i];
    const bool first = i == 0;
    SignalChain c;
    c.suffix = s.suffix;
    c.signal = v.extra_samples ? mixed_signal(s.input) : s.input;
    c.modulator = s.modulator.buffer;
    c.client_divided = s.modulator.client_divided;
    if (s.subtract_emission) c.emission = kEmissionPlane;
    // One persistent copy each, read by svgf_reproject and rewritten after it
    // by svgf_variance and the feedback a-trous iteration.
    c.colour_history = s.history + "_colour";
    c.aux_history = s.history + "_aux";
    // A later signal shares the first's guide unless it has features of its own.
    c.guide = first || !s.features ? kGuide : kGuide + s.suffix;
    c.temporal = first ? kTemporal : kTemporal + s.suffix;
    c.illum = first ? kIllumA : kIllumC;
    c.other = first ? kIllumB : kIllumD;
    // Features: the signal's own, the caller's primary ones (a filled sparse G-buffer) or the planes.
    c.depth = s.features ? s.features->depth : primary_depth(v);
    c.normal = s.features ? s.features->normal : v.primary_features ? v.primary_features->normal : kNormalPlane;
    c.motion = kMotionPlane;
    if (s.motion == MotionSource::Reflection) c.reflection_motion = s.reflection_motion;
    // Read and rewritten at p by svgf_reproject.
    if (keeps_still_mean(v)) {
      c.still_mean = s.history + "_still";
      c.still_m2 = s.history + "_still_m2";
      c.still_change = s.history + "_still_change";
    }
    chains.push_back(std::move(c));
  }
  return chains;
}

std::vector<std::string> guard_partners(const SvgfVariant& v) {
  if (!v.harm_guard || v.iterations < 2) return {};
  std::vector<std::string> partners = {kIllumE, kIllumF};
  partners.resize(v.signals.size());
  return partners;
}

}  // namespace svgf

using namespace svgf;

void add_svgf_inputs(GraphSpec& g, const SessionConfig& config, const SvgfVariant& v) {
  for (const SvgfSignal& s : v.signals) g.add_input(config, s.channel, s.input);
  for (const SvgfSignal& s : v.signals)
    if (s.modulator.plane && !g.find(s.modulator.buffer)) g.add_input(config, *s.modulator.plane, s.modulator.buffer);
  g.add_input(config, ChannelId::Normal, kNormalPlane);
  g.add_input(config, ChannelId::Depth, kDepthPlane);
  g.add_input(config, ChannelId::Motion, kMotionPlane);
  if (v.emission) g.add_input(config, ChannelId::Emission, kEmissionPlane);
  if (v.validity_mask) g.add_input(config, *v.validity_mask, kSampleCountPlane);
  if (v.roughness && !g.find(kRoughnessPlane)) g.add_input(config, ChannelId::Roughness, kRoughnessPlane);
  if (v.extra_samples) {
    std::vector<ChannelId> channels;
    for (const SvgfSignal& s : v.signals) channels.push_back(s.channel);
    add_supersample_inputs(g, config, channels);
  }
}

void add_svgf_buffers(GraphSpec& g, const SvgfVariant& v) {
  const std::vector<SignalChain> chains = signal_chains(v);
  for (const SignalChain& c : chains) {
    g.add_persistent(c.colour_history);
    g.add_persistent(c.aux_history);
    if (!c.still_mean.empty()) {
      g.add_persistent(c.still_mean);
      g.add_persistent(c.still_m2);
      g.add_persistent(c.still_change);
    }
  }
  if (keeps_still_emission(v)) {
    g.add_persistent(kEmissionStill);
    g.add_persistent(kEmissionTest);
  }
  if (v.taa) {
    g.add_persistent(kTaaHistory);
    g.add_alias(kTaaCurrent, kTemporal);
    g.add_alias(kTaaPrevious, kGuide);
  }
  if (!v.display.empty()) g.add_scratch(v.display);
  if (v.extra_samples) {
    std::vector<std::string> inputs;
    for (const SvgfSignal& s : v.signals) inputs.push_back(s.input);
    add_supersample_buffers(g, inputs);
    g.add_scratch(kSupersampleDisplay);
  }
  const std::vector<std::string> partners = guard_partners(v);
  for (size_t i = 0; i < chains.size(); ++i) {
    g.add_scratch(chains[i].illum);
    if (v.iterations > 0) g.add_scratch(chains[i].other);
    if (!partners.empty()) g.add_scratch(partners[i]);
  }
  // One guide and temporal per signal (the joint passes read both), but a
  // later signal without features of its own shares the first's guide.
  for (size_t i = 0; i < chains.size(); ++i) {
    if (i == 0 || chains[i].guide != chains[0].guide) g.add_scratch(chains[i].guide);
    g.add_scratch(chains[i].temporal);
  }
  if (clips(v)) {
    g.add_scratch(kClipCurrent);
    g.add_scratch(kClipPartial);
    g.add_scratch(kClipNeighbourhood);
  }
}

std::string still_mean_buffer(const SvgfVariant& v) {
  return keeps_still_mean(v) ? signal_chains(v)[0].still_mean : "";
}
std::string still_m2_buffer(const SvgfVariant& v) { return keeps_still_mean(v) ? signal_chains(v)[0].still_m2 : ""; }

}  // namespace dn::pipelines
