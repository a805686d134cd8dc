#include "pipelines/stages/svgf_chain.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

#include "pipelines/definitions.hpp"
#include "pipelines/sample_summary.hpp"
#include "pipelines/stages/supersample.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

// Per pixel, a single persistent copy (svgf_reproject reads it; svgf_variance
// and the feedback a-trous iteration rewrite it after that pass):
// vec4(demodulated rgb, length) fp32 and uvec4(m1, m2, depth as fp32 bits,
// octahedral snorm16x2 normal).
constexpr uint64_t kColourHistoryBytes = 16;
constexpr uint64_t kAuxHistoryBytes = 16;
// converge_still: a still pixel's running mean of its own samples,
// vec4(demodulated rgb, samples), the M2 of their luminance, and its change
// test's vec4(running mean, M2, recent mean, recent spread variance) of the
// 3x3 box luminance, fp32, read and rewritten at p by svgf_reproject.
constexpr uint64_t kStillMeanBytes = 16;
constexpr uint64_t kStillM2Bytes = 4;
constexpr uint64_t kStillChangeBytes = 16;
// With emission: a still pixel's running mean of its emission, vec4(rgb,
// samples), and its change test's (M2 of the luminance, suspect), fp32, one
// copy each, read and rewritten at p by svgf_remodulate.
constexpr const char* kEmissionStill = "emission_still";
constexpr const char* kEmissionTest = "emission_test";
constexpr uint64_t kEmissionStillBytes = 16;
constexpr uint64_t kEmissionTestBytes = 8;
// TAA: the previous final output and, with SvgfVariant::display_lag, the
// lag state: vec4(rgb, lag) fp32, one persistent copy (read as texels by
// svgf_remodulate, rewritten by svgf_taa after it).
constexpr uint64_t kTaaHistoryBytes = 16;
// SvgfVariant::display: the displayed frame, vec4(rgb, 0) fp32 (a texel
// for the caller's neighbourhood reads: reflect_median).
constexpr uint64_t kDisplayBytes = 16;
// Scratch, per pixel: vec4(demodulated rgb, variance) fp32, two for the a-trous ping-pong.
constexpr uint64_t kIlluminationBytes = 16;
// Scratch, per pixel: guide uvec4(signed depth, packed normal, dz, 0) and
// temporal vec4(m1, m2, length, luminance), written by svgf_reproject.
constexpr uint64_t kGuideBytes = 16;
constexpr uint64_t kTemporalBytes = 16;
// a-trous register block: one invocation filters kAtrousBlock^2 pixels.
constexpr uint32_t kAtrousBlock = 4;

// Illumination ping-pong of the first signal (a, b) and of the second (c, d).
constexpr const char* kIllumA = "svgf_illum_a";
constexpr const char* kIllumB = "svgf_illum_b";
constexpr const char* kIllumC = "svgf_illum_c";
constexpr const char* kIllumD = "svgf_illum_d";
// With the harm guard, the a-trous iterations after the first ping-pong
// between b and e (d and f), so a (c) keeps the variance pass's output.
constexpr const char* kIllumE = "svgf_illum_e";
constexpr const char* kIllumF = "svgf_illum_f";
// The first signal's guide and temporal; the second's temporal, and its
// guide when it has its own features, are these names + its suffix (both
// signals' are read by the joint a-trous passes).
constexpr const char* kGuide = "svgf_guide";
constexpr const char* kTemporal = "svgf_temporal";
constexpr const char* kTaaHistory = "svgf_taa";
// History clipping scratch, per pixel, shared by the clipped signals (each
// signal's reprojection reads it before the next signal's prefilter
// rewrites it): the demodulated current signal vec4(rgb, foreground), the
// horizontal pass's vec4(sum w c, sum w) and the box source
// vec4(prefiltered rgb, foreground), fp32.
constexpr const char* kClipCurrent = "svgf_clip_current";
constexpr const char* kClipPartial = "svgf_clip_partial";
constexpr const char* kClipNeighbourhood = "svgf_clip_neighbourhood";
constexpr uint64_t kClipBytes = 16;
// sparse_gbuffer: the packed 3x3 pyramid (gbuffer_fill.comp) of vec4(normal,
// depth) fp32 and its validity (uint), and the filled planes the chain reads
// instead of depth and normal, fp32 (1 and 3 per pixel).
constexpr const char* kGbufferPyramid = "gbuffer_pyramid";
constexpr const char* kGbufferValid = "gbuffer_valid";
constexpr const char* kFilledDepth = "gbuffer_depth";
constexpr const char* kFilledNormal = "gbuffer_normal";
constexpr uint32_t kGbufferFactor = 3;

uint32_t modulator_half(const SessionConfig& config, const Modulator& m) {
  return m.plane ? is_half(channel_format(config, *m.plane)) : 0u;
}

// The buffer a chain reads its signal from: the plane, or with extra samples
// supersample_mix's fp32 result.
std::string signal_buffer(const SvgfVariant& v, const SvgfSignal& s) {
  return v.extra_samples ? mixed_signal(s.input) : s.input;
}
uint32_t signal_half(const SessionConfig& config, const SvgfVariant& v, const SvgfSignal& s) {
  return v.extra_samples ? 0u : is_half(channel_format(config, s.channel));
}

// The passes of the separable 7x7 prefilter history clipping takes its box
// from: the demodulated current signal once per pixel, rows, columns.
void add_clip_prefilter(GraphSpec& g, const SessionConfig& config, const SvgfVariant& v, const SvgfSignal& s,
                        bool demodulate) {
  PassSpec& current = g.add_pass("svgf_clip_current" + s.suffix, "svgf_clip_prefilter");
  current.bind("signal", signal_buffer(v, s))
      .bind("depth", "depth")
      .bind("dst", kClipCurrent)
      .set("MODE", 0u)
      .set("SIGNAL_HALF", signal_half(config, v, s))
      .set("DEPTH_HALF", is_half(channel_format(config, ChannelId::Depth)))
      .set("DEMODULATE", demodulate)
      .set("MODULATOR_HALF", demodulate ? modulator_half(config, s.modulator) : 0u)
      .set("SUBTRACT_EMISSION", s.subtract_emission);
  if (demodulate) current.bind("modulator", s.modulator.buffer);
  if (s.subtract_emission)
    current.bind("emission", "emission").set("EMISSION_HALF", is_half(channel_format(config, ChannelId::Emission)));
  current.pixels_per_invocation = 1;
  g.add_pass("svgf_clip_prefilter_x" + s.suffix, "svgf_clip_prefilter")
      .bind("src", kClipCurrent)
      .bind("dst", kClipPartial)
      .set("MODE", 1u)
      .pixels_per_invocation = 1;
  g.add_pass("svgf_clip_prefilter_y" + s.suffix, "svgf_clip_prefilter")
      .bind("src", kClipPartial)
      .bind("dst", kClipNeighbourhood)
      .set("MODE", 2u)
      .pixels_per_invocation = 1;
}

// The sample_count plane as a pass's validity mask (MASKED).
void bind_validity_mask(const SessionConfig& config, ChannelId mask, PassSpec& pass) {
  pass.bind("sample_count", "sample_count").set("MASKED", 1u).set("SAMPLE_COUNT_HALF", is_half(channel_format(config, mask)));
}

// The number of levels above level 0 of the 3x3 pyramid: down to one pixel.
uint32_t gbuffer_levels(const SessionConfig& config) {
  uint32_t levels = 0;
  for (uint32_t side = std::max(config.width, config.height); side > 1; side = (side + kGbufferFactor - 1) / kGbufferFactor)
    ++levels;
  return levels;
}

// gbuffer_fill: seed level 0 from the planes, pull to the coarsest level,
// push back down; the push at level 0 writes the filled planes.
void add_gbuffer_fill(GraphSpec& g, const SessionConfig& config, ChannelId mask) {
  const uint32_t levels = gbuffer_levels(config);
  auto args = [&](uint32_t level) {
    return std::array<uint32_t, 4>{level, kGbufferFactor, config.width, config.height};
  };
  const gpu::Extent full = g.level(kGbufferFactor, 0);
  g.add_pass("gbuffer_seed", "gbuffer_fill")
      .bind("depth", "depth")
      .bind("normal", "normal")
      .bind("sample_count", "sample_count")
      .bind("pyramid", kGbufferPyramid)
      .bind("valid", kGbufferValid)
      .set("MODE", 0u)
      .set("DEPTH_HALF", is_half(channel_format(config, ChannelId::Depth)))
      .set("NORMAL_HALF", is_half(channel_format(config, ChannelId::Normal)))
      .set("SAMPLE_COUNT_HALF", is_half(channel_format(config, mask)))
      .over_grid(full, full, args(0));
  for (uint32_t l = 1; l <= levels; ++l)
    g.add_pass("gbuffer_pull_" + std::to_string(l), "gbuffer_fill")
        .bind("pyramid", kGbufferPyramid)
        .bind("valid", kGbufferValid)
        .set("MODE", 1u)
        .over_grid(g.level(kGbufferFactor, l), g.level(kGbufferFactor, l - 1), args(l));
  for (uint32_t l = levels; l-- > 0;) {
    PassSpec& push = g.add_pass("gbuffer_push_" + std::to_string(l), "gbuffer_fill");
    push.bind("pyramid", kGbufferPyramid)
        .bind("valid", kGbufferValid)
        .set("MODE", 2u)
        .over_grid(g.level(kGbufferFactor, l), g.level(kGbufferFactor, l + 1), args(l));
    if (l == 0) push.bind("filled_depth", kFilledDepth).bind("filled_normal", kFilledNormal);
  }
}

// The scratch buffers of signal `index`.
struct SignalBuffers {
  std::string guide, temporal;
  std::string illum, other;  // the a-trous ping-pong: illum holds the reprojected signal
};
SignalBuffers signal_buffers(const SvgfVariant& v, size_t index) {
  if (index == 0) return {kGuide, kTemporal, kIllumA, kIllumB};
  const SvgfSignal& s = v.signals[index];
  return {s.features ? kGuide + s.suffix : kGuide, kTemporal + s.suffix, kIllumC, kIllumD};
}

// The joint passes' second-signal geometry (svgf_joint.glsl): its temporal
// scratch and, when it is not the first's, its own guide (SECOND_GUIDE).
void bind_second_geometry(PassSpec& pass, const SignalBuffers& first, const SignalBuffers& second) {
  pass.bind("temporal2", second.temporal);
  if (second.guide != first.guide) pass.bind("guide2", second.guide).set("SECOND_GUIDE", 1u);
}

// The still pixels' running means are kept where the harm guard reads them.
bool keeps_still_mean(const SvgfVariant& v) { return v.converge_still && v.harm_guard && v.iterations > 0; }
// And of the emission, which is added back unfiltered.
bool keeps_still_emission(const SvgfVariant& v) { return v.emission && keeps_still_mean(v); }
// A signal's still running mean (vec4(mean, n)) and the M2 of its samples' luminance.
std::string still_mean_of(const std::string& history) { return history + "_still"; }
std::string still_m2_of(const std::string& history) { return history + "_still_m2"; }
std::string still_change_of(const std::string& history) { return history + "_still_change"; }

// Signal `index`'s reprojection (and history clipping): its temporal colour
// in its illum buffer, its temporal moments and length.
void add_reprojection(GraphSpec& g, const SessionConfig& config, const SvgfVariant& v, size_t index) {
  const SvgfSignal& s = v.signals[index];
  const SignalBuffers buffers = signal_buffers(v, index);
  const std::string colour = s.history + "_colour", aux = s.history + "_aux";
  const bool demodulate = !s.modulator.empty() && !s.modulator.client_divided;
  // Features: the signal's own (fp32 buffers), the filled sparse G-buffer
  // (fp32 buffers) or the primary planes.
  const bool own = s.features.has_value() || v.sparse_gbuffer;
  const std::string depth = s.features ? s.features->depth : v.sparse_gbuffer ? kFilledDepth : "depth";
  const std::string normal = s.features ? s.features->normal : v.sparse_gbuffer ? kFilledNormal : "normal";
  const uint32_t normal_half = own ? 0u : is_half(channel_format(config, ChannelId::Normal));
  const uint32_t depth_half = own ? 0u : is_half(channel_format(config, ChannelId::Depth));
  const bool clip = v.clip && s.clip;
  if (clip) add_clip_prefilter(g, config, v, s, demodulate);

  PassSpec& reproject = g.add_pass("svgf_reproject" + s.suffix, "svgf_reproject");
  reproject.bind("signal", signal_buffer(v, s))
      .bind("normal", normal)
      .bind("depth", depth)
      .bind("motion", "motion")
      .bind("prev_colour", colour)
      .bind("prev_aux", aux)
      .bind("illum", buffers.illum)
      .bind("guide", buffers.guide)
      .bind("temporal", buffers.temporal)
      .set("SIGNAL_HALF", signal_half(config, v, s))
      .set("MODULATOR_HALF", demodulate ? modulator_half(config, s.modulator) : 0u)
      .set("NORMAL_HALF", normal_half)
      .set("DEPTH_HALF", depth_half)
      .set("MOTION_HALF", is_half(channel_format(config, ChannelId::Motion)))
      .set("DEMODULATE", demodulate)
      .set("WRITE_GUIDE", index == 0 || s.features.has_value())  // else: the first signal's guide
      .set("SUBTRACT_EMISSION", s.subtract_emission)
      .set("READ_HISTORY", s.reads_history)
      .set("SPECULAR_ALPHA", s.specular_alpha);
  if (demodulate) reproject.bind("modulator", s.modulator.buffer);
  if (keeps_still_mean(v))
    reproject.bind("still_mean", still_mean_of(s.history))
        .bind("still_m2", still_m2_of(s.history))
        .bind("still_change", still_change_of(s.history))
        .set("CONVERGE_STILL", 1u);
  // A signal on the reflected hit's features keeps its still mean while the pixel's surface does.
  if (keeps_still_mean(v) && index > 0 && s.features)
    reproject.bind("surface_still", still_mean_of(v.signals[0].history)).set("SURFACE_STILL", 1u);
  if (s.subtract_emission)
    reproject.bind("emission", "emission").set("EMISSION_HALF", is_half(channel_format(config, ChannelId::Emission)));
  if (clip)
    reproject.bind("neighbourhood", kClipNeighbourhood)
        .bind("current", kClipCurrent)
        .bind("roughness", "roughness")
        .set("CLIP", 1u)
        .set("ROUGHNESS_HALF", is_half(channel_format(config, ChannelId::Roughness)));
  if (s.motion == MotionSource::Reflection) reproject.bind("reflection", s.reflection_motion).set("REFLECTION", 1u);
  if (v.validity_mask) bind_validity_mask(config, *v.validity_mask, reproject);
  reproject.pixels_per_invocation = 1;
}

// The variance of every signal in one pass (the joint chain: the guide's
// loads and the 7x7 estimate's geometric weights shared), which also writes
// each signal's history for the next frame.
void add_variance(GraphSpec& g, const SvgfVariant& v) {
  const SignalBuffers first = signal_buffers(v, 0);
  PassSpec& variance = g.add_pass("svgf_variance", "svgf_variance");
  variance.bind("guide", first.guide)
      .bind("temporal", first.temporal)
      .bind("illum", first.illum)
      .bind("colour_history", v.signals[0].history + "_colour")
      .bind("aux_history", v.signals[0].history + "_aux")
      .set("SPATIAL_ESTIMATE", v.young_variance == YoungVariance::SpatialEstimate)
      .set("SIGNALS", static_cast<uint32_t>(v.signals.size()));
  variance.pixels_per_invocation = 1;
  if (v.signals.size() > 1) {
    const SignalBuffers second = signal_buffers(v, 1);
    variance.bind("illum2", second.illum)
        .bind("colour_history2", v.signals[1].history + "_colour")
        .bind("aux_history2", v.signals[1].history + "_aux");
    bind_second_geometry(variance, first, second);
  }
}

// The a-trous iterations, every signal in the same passes (the joint chain:
// the guide's loads and geometric weights shared); returns the buffer
// holding each signal's final illumination.
std::vector<std::string> add_atrous(GraphSpec& g, const SessionConfig& config, const SvgfVariant& v) {
  std::vector<SignalBuffers> buffers;
  for (size_t i = 0; i < v.signals.size(); ++i) buffers.push_back(signal_buffers(v, i));
  const bool two = v.signals.size() > 1;
  const SvgfSignal& last = v.signals.back();
  const uint32_t tap = std::min(v.feedback_tap, v.iterations ? v.iterations - 1 : 0u);
  for (uint32_t i = 0; i < v.iterations; ++i) {
    const uint32_t level = step_level(v.steps, i, v.iterations);
    PassSpec& atrous = g.add_pass("svgf_atrous_" + std::to_string(i), "svgf_atrous");
    atrous.bind("guide", buffers[0].guide)
        .bind("src", buffers[0].illum)
        .bind("dst", buffers[0].other)
        .bind("temporal", buffers[0].temporal)
        .set("STEP", 1u << level)
        .set("FEEDBACK", i == tap)
        .set("BLOCK", kAtrousBlock)
        .set("CLASS_EDGES", last.motion == MotionSource::Reflection)
        .set("KERNEL_RADIUS", v.kernel == AtrousKernel::B3_5x5 ? 2u : 1u)
        .set("LUMINANCE_VARIANCE", v.luminance_weight == LuminanceWeight::Variance)
        .set("AGE_GATED_LUMINANCE", v.young_variance == YoungVariance::LuminanceOff)
        .set("DISPLAY_FILL", v.validity_mask.has_value() && i + 1 == v.iterations)
        .set("SIGNALS", static_cast<uint32_t>(v.signals.size()))
        .set("NORMAL_POWER", static_cast<uint32_t>(v.normal_power))
        .set("LUMINANCE_RAMP", v.luminance_ramp);
    if (i == tap) atrous.bind("colour_history", v.signals[0].history + "_colour");
    if (two) {
      atrous.bind("src2", buffers[1].illum).bind("dst2", buffers[1].other);
      if (i == tap) atrous.bind("colour_history2", v.signals[1].history + "_colour");
      bind_second_geometry(atrous, buffers[0], buffers[1]);
    }
    if (i == tap && v.validity_mask) bind_validity_mask(config, *v.validity_mask, atrous);
    if (!last.spatial_bandwidth.empty()) atrous.bind("bandwidth", last.spatial_bandwidth).set("SPATIAL_BANDWIDTH", 1u);
    // Grid of server/pipelines/stages/svgf_atrous.comp: (ceil(W / span) * step) x (ceil(H / span) * step), span = step * block.
    const uint64_t step = uint64_t{1} << level, span = step * kAtrousBlock;
    atrous.invocations = ((config.width + span - 1) / span * step) * ((config.height + span - 1) / span * step);
    for (SignalBuffers& b : buffers) std::swap(b.illum, b.other);
    if (i == 0 && v.harm_guard)
      for (size_t s = 0; s < buffers.size(); ++s) buffers[s].other = s == 0 ? kIllumE : kIllumF;
  }
  std::vector<std::string> results;
  for (const SignalBuffers& b : buffers) results.push_back(b.illum);
  return results;
}

}  // namespace

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
  if (v.sparse_gbuffer && !v.validity_mask) reject("a sparse G-buffer needs the validity mask that says where it has data");
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
    g.add_persistent(s.history + "_colour", kColourHistoryBytes);
    g.add_persistent(s.history + "_aux", kAuxHistoryBytes);
    if (keeps_still_mean(v)) {
      g.add_persistent(still_mean_of(s.history), kStillMeanBytes);
      g.add_persistent(still_m2_of(s.history), kStillM2Bytes);
      g.add_persistent(still_change_of(s.history), kStillChangeBytes);
    }
  }
  if (keeps_still_emission(v)) {
    g.add_persistent(kEmissionStill, kEmissionStillBytes);
    g.add_persistent(kEmissionTest, kEmissionTestBytes);
  }
  if (v.taa) g.add_persistent(kTaaHistory, kTaaHistoryBytes);
  if (!v.display.empty()) g.add_scratch(v.display, kDisplayBytes);
  if (v.extra_samples) {
    std::vector<std::string> inputs;
    for (const SvgfSignal& s : v.signals) inputs.push_back(s.input);
    add_supersample_buffers(g, inputs);
    g.add_scratch(kSupersampleDisplay, kSupersampleDisplayBytes);
  }
  const bool third = v.harm_guard && v.iterations > 1;  // the guard's own ping-pong partner
  g.add_scratch(kIllumA, kIlluminationBytes);
  if (v.iterations > 0) g.add_scratch(kIllumB, kIlluminationBytes);
  if (third) g.add_scratch(kIllumE, kIlluminationBytes);
  if (v.signals.size() > 1) {
    g.add_scratch(kIllumC, kIlluminationBytes);
    if (v.iterations > 0) g.add_scratch(kIllumD, kIlluminationBytes);
    if (third) g.add_scratch(kIllumF, kIlluminationBytes);
  }
  if (v.sparse_gbuffer) {
    const uint64_t elements = gpu::pyramid_pixels(g.width, g.height, kGbufferFactor);
    g.add_scratch_elements(kGbufferPyramid, elements, 16);
    g.add_scratch_elements(kGbufferValid, elements, 4);
    g.add_scratch(kFilledDepth, 4);
    g.add_scratch(kFilledNormal, 12);
  }
  // One guide and temporal per signal (the joint a-trous passes read both),
  // except that a second signal without features of its own shares the guide.
  for (size_t i = 0; i < v.signals.size(); ++i) {
    const SignalBuffers b = signal_buffers(v, i);
    if (i == 0 || b.guide != kGuide) g.add_scratch(b.guide, kGuideBytes);
    g.add_scratch(b.temporal, kTemporalBytes);
  }
  const bool clips = v.clip && std::any_of(v.signals.begin(), v.signals.end(), [](const SvgfSignal& s) { return s.clip; });
  if (clips) {
    g.add_scratch(kClipCurrent, kClipBytes);
    g.add_scratch(kClipPartial, kClipBytes);
    g.add_scratch(kClipNeighbourhood, kClipBytes);
  }
}

void add_svgf_passes(GraphSpec& g, const SessionConfig& config, const SvgfVariant& v) {
  check_supported(v);
  if (v.extra_samples) {
    add_supersample_assign(g, config);
    for (const SvgfSignal& s : v.signals) add_supersample_mix(g, config, s.channel, s.input, s.suffix);
  }
  if (v.sparse_gbuffer) add_gbuffer_fill(g, config, *v.validity_mask);
  for (size_t i = 0; i < v.signals.size(); ++i) add_reprojection(g, config, v, i);
  add_variance(g, v);
  const std::vector<std::string> results = add_atrous(g, config, v);

  // With TAA, svgf_remodulate writes the current colour to the temporal
  // scratch and the reprojected TAA history to the guide scratch (both free
  // once the a-trous chains are done) instead of Output; svgf_taa blends them.
  // Without it, the TAA bindings stay unbound.
  const Modulator& first = v.signals[0].modulator;
  // Output, or a scratch frame for the caller's pass or the resolve.
  const bool direct = v.display.empty() && !v.extra_samples;
  const std::string result = v.extra_samples ? kSupersampleDisplay : "output";
  const uint32_t result_half = direct ? is_half(config.output_format) : 0u;
  // The last pass's frame: Output (or the resolve's), or the caller's display.
  auto bind_result = [&](PassSpec& pass) {
    if (v.display.empty()) pass.bind("result", result).set("OUTPUT_HALF", result_half);
    else pass.bind("display", v.display).set("TO_DISPLAY", 1u);
  };
  PassSpec& remodulate = g.add_pass("svgf_remodulate", "svgf_remodulate");
  remodulate.bind("illum", results[0])
      .bind("albedo", first.buffer)
      .set("ALBEDO_HALF", modulator_half(config, first))
      .set("HAS_EMISSION", v.emission)
      .set("HAS_SPECULAR", v.signals.size() > 1)
      .set("TAA", v.taa);
  if (!v.taa) bind_result(remodulate);
  if (v.emission)
    remodulate.bind("emission", "emission").set("EMISSION_HALF", is_half(channel_format(config, ChannelId::Emission)));
  if (keeps_still_emission(v))
    remodulate.bind("emission_still", kEmissionStill).bind("emission_test", kEmissionTest).set("EMISSION_STILL", 1u);
  if (v.signals.size() > 1) {
    remodulate.bind("specular", results[1]);
    const Modulator& second = v.signals[1].modulator;
    if (!second.empty())
      remodulate.bind("specular_factor", second.buffer)
          .set("SPECULAR_FACTOR", 1u)
          .set("SPECULAR_FACTOR_HALF", modulator_half(config, second));
  }
  // keep: the (diffuse) albedo must be a client plane, the test's input; with
  // a validity mask only sampled pixels have a current radiance to keep.
  const bool radiance = v.signals.size() == 1 && v.signals[0].channel == ChannelId::Radiance;
  const bool keep = v.keep_unexplained && (radiance || v.signals.size() == 2) && !v.extra_samples &&
                    first.plane == ChannelId::Albedo;
  // Motion: the TAA reprojection's, a still unexplained pixel's history (with the guard's buffer), still emission.
  if (v.taa || keep || keeps_still_emission(v)) remodulate.bind("motion", "motion").set("MOTION_HALF", is_half(channel_format(config, ChannelId::Motion)));
  // Depth: the TAA's foreground test, still emission's (a background pixel keeps no mean).
  if (v.taa || keeps_still_emission(v))
    remodulate.bind("depth", v.sparse_gbuffer ? kFilledDepth : "depth")
        .set("DEPTH_HALF", v.sparse_gbuffer ? 0u : is_half(channel_format(config, ChannelId::Depth)));
  if (v.taa) remodulate.bind("taa_history", kTaaHistory).bind("taa_current", kTemporal).bind("taa_previous", kGuide);
  const bool guard = v.harm_guard && v.iterations > 0;
  // The first chain's history (its length): read by the display lag and the harm guard.
  if (v.display_lag || guard) remodulate.bind("colour_history", v.signals[0].history + "_colour");
  if (v.display_lag) remodulate.set("DISPLAY_LAG", 1u);
  if (keep) {
    remodulate.bind("raw", v.signals[0].input)
        .set("KEEP_UNEXPLAINED", 1u)
        .set("RAW_HALF", is_half(channel_format(config, v.signals[0].channel)))
        .set("RAW_DIVIDED", first.client_divided);
    if (v.validity_mask) bind_validity_mask(config, *v.validity_mask, remodulate);
    if (v.signals.size() > 1)
      remodulate.bind("raw2", v.signals[1].input)
          .set("RAW2_HALF", is_half(channel_format(config, v.signals[1].channel)))
          .set("RAW2_DIVIDED", v.signals[1].modulator.client_divided);
  }
  if (guard) {
    remodulate.bind("own", signal_buffers(v, 0).illum).set("HARM_GUARD", 1u);
    if (v.signals.size() > 1)
      remodulate.bind("own2", signal_buffers(v, 1).illum).bind("colour_history2", v.signals[1].history + "_colour");
    if (keeps_still_mean(v)) {
      remodulate.bind("still_mean", still_mean_of(v.signals[0].history))
          .bind("still_m2", still_m2_of(v.signals[0].history))
          .set("CONVERGE_STILL", 1u);
      if (v.signals.size() > 1)
        remodulate.bind("still_mean2", still_mean_of(v.signals[1].history))
            .bind("still_m2_2", still_m2_of(v.signals[1].history))
            .set("SPECULAR_ALPHA", v.signals[1].specular_alpha);
    }
  }

  if (v.taa) {
    PassSpec& taa = g.add_pass("svgf_taa", "svgf_taa");
    taa.bind("current", kTemporal).bind("previous", kGuide).bind("history", kTaaHistory)
        .bind("depth", v.sparse_gbuffer ? kFilledDepth : "depth")
        .set("DEPTH_HALF", v.sparse_gbuffer ? 0u : is_half(channel_format(config, ChannelId::Depth)));
    bind_result(taa);
    if (v.display_lag) taa.set("DISPLAY_LAG", 1u);
  }
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
