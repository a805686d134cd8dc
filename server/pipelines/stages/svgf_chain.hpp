// The SVGF pass chain as a reusable builder (docs/pipelines.md, "svgf in
// detail"): per signal svgf_reproject -> svgf_variance, then the a-trous
// iterations svgf_atrous_<i>, which filter every signal (split diffuse and
// specular: the joint chain) in the same passes, then svgf_remodulate and,
// with TAA, svgf_taa. What varies between
// pipelines is data, an SvgfVariant: the signals (each with its modulator and
// motion source), the a-trous kernel, step order and luminance weight, the
// feedback tap, a validity mask, TAA and emission; per signal its motion
// source and its edge-stopping features. svgf and svgf-fb are two
// variant descriptions (svgf.cpp, svgf_fb.cpp); builders never compare
// pipeline names. Fields the shaders do not support yet are part of the
// description and rejected by check_supported() with a message naming them.
// add_svgf_passes translates the variant into the stages of svgf_stages.hpp,
// each a function over named buffers, and calls them in order.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "pipelines/graph.hpp"

namespace dn::pipelines {

// The a-trous filter kernel.
enum class AtrousKernel {
  B3_5x5,  // the B3 spline {1/16, 1/4, 3/8, 1/4, 1/16}^2 (Schied 2017; svgf_atrous.comp)
  Box3x3,  // the 3x3 {1/4, 1/2, 1/4}^2 (paper 004 §4.4)
};
// Order of the a-trous step sizes 2^i over the iterations.
enum class StepOrder {
  Increasing,   // 1, 2, 4, ... (Schied 2017)
  Decreasing,   // ..., 4, 2, 1 (coarse to fine)
  FinestFirst,  // 1, then coarse to fine: 1, 2^(n-1), ..., 4, 2 (paper 004 §4.4: the first feeds the history)
};
// The luminance edge-stopping weight of the a-trous passes.
enum class LuminanceWeight {
  VarianceGuided,  // |l_p - l_q| / (phi_colour * sqrt(3x3 Gaussian of the variance + eps)) (Schied 2017)
  Variance,        // |l_p - l_q| / (sigma_luminance * 3x3 Gaussian of the variance + epsilon_luminance) (paper 004)
};
// What stands in for a young pixel's (history length < 4) temporal variance.
enum class YoungVariance {
  SpatialEstimate,  // Falcor's 7x7 estimate from the neighbours' moments (svgf_variance)
  LuminanceOff,     // none: no luminance weight while length < luminance_min_age (paper 004 §4.4.3)
};
// Where a signal's reprojection takes its motion from.
enum class MotionSource {
  Primary,     // the Motion plane
  Reflection,  // reflect_motion's buffer (paper 001): SvgfSignal::reflection_motion
};

// A signal's own edge-stopping and history-test features, instead of the
// primary depth and normal planes: fp32 buffers of 1 and 3 components per
// pixel that the caller writes (reflect's specular chain: the reflected
// surface's at mirrors). A chain with its own features writes its own guide.
struct SignalFeatures {
  std::string depth, normal;
};

// What a signal is divided by before filtering and multiplied by after
// (both guarded: components below 1e-3 or not finite count as 1).
struct Modulator {
  std::string buffer;   // a graph buffer with 3 components per pixel; empty: none (factor 1)
  // Set: the buffer is this client plane (add_svgf_inputs adds it). Unset: a
  // buffer the caller provides.
  std::optional<protocol::ChannelId> plane;
  bool client_divided = false;  // the client sent the signal divided already: multiply only
  bool empty() const { return buffer.empty(); }
};

struct SvgfSignal {
  protocol::ChannelId channel = protocol::ChannelId::Radiance;  // its plane
  std::string input;            // the plane's buffer
  std::string suffix;           // of its passes' names ("" with one signal, "_diffuse", ...)
  std::string history;          // prefix of its history buffers: <history>_colour, <history>_aux
  Modulator modulator;
  MotionSource motion = MotionSource::Primary;
  std::string reflection_motion;  // Reflection: the buffer of vec4(motion, class, distance) (reflect_motion)
  std::optional<SignalFeatures> features;
  bool subtract_emission = false;  // the signal includes emission (radiance): filter it without
  bool clip = false;               // its history is clipped (highlights and reflections: radiance, specular)
  bool reads_history = true;       // false: filtered from the current frame alone (a NoSpecReproj baseline)
  bool specular_alpha = false;     // blends with alpha_specular (group specular), not svgf's alpha_colour
  // Set: an fp32 buffer of per-pixel sigma (0: none) that adds a Gaussian on
  // the a-trous tap offsets, in steps (reflect's Eq. 6; SPATIAL_BANDWIDTH).
  std::string spatial_bandwidth;
};

struct SvgfVariant {
  std::vector<SvgfSignal> signals;  // the first writes the guide the others read
  AtrousKernel kernel = AtrousKernel::B3_5x5;
  StepOrder steps = StepOrder::Increasing;
  LuminanceWeight luminance_weight = LuminanceWeight::VarianceGuided;
  YoungVariance young_variance = YoungVariance::SpatialEstimate;
  uint32_t iterations = 4;           // a-trous iterations (0: none)
  uint32_t feedback_tap = 1;         // iteration whose output becomes the colour history (clamped)
  // Set: this plane (sample_count) says which pixels have a sample this
  // frame; the others keep their history as it is, and a pixel with neither
  // has no data, which no neighbour takes (paper 004 §5; svgf_reproject's MASKED).
  std::optional<protocol::ChannelId> validity_mask;
  // Set: the depth and normal every pass of the chain reads instead of the
  // planes (a signal's own features aside), buffers of 1 and 3 fp32 per
  // pixel that the caller's passes write before the chain's (progressive's
  // G-buffer filled where a sparse one has no sample).
  std::optional<SignalFeatures> primary_features;
  bool taa = false;                  // final svgf_taa pass
  // With taa: the display one step behind where a still pixel's history
  // switches source (progressive's display_lag; svgf_remodulate's display_lag).
  bool display_lag = false;
  bool emission = false;             // add the Emission plane back after filtering
  bool roughness = false;            // the session has a Roughness plane (an input)
  bool clip = false;                 // clip the signals marked clip where roughness < clip_roughness (needs roughness)
  // k when phi_normal is exactly 2^k (k = 0..kMaxNormalPower), else -1: the
  // a-trous normal weight max(0, cos)^phi_normal by k squarings instead of
  // exp2(phi_normal * log2(cos)) (svgf_atrous.pass, NORMAL_POWER).
  int32_t normal_power = -1;
  bool luminance_ramp = false;       // luminance_ramp != 0 (svgf_atrous.pass, LUMINANCE_RAMP)
  // harm_guard > 0: svgf_remodulate pulls each filtered signal back toward
  // its own temporal mean (the variance pass's output, which the a-trous
  // ping-pong then leaves intact).
  bool harm_guard = false;
  // keep_unexplained != 0: pixels whose albedo plane is not a reflectance
  // (zero under a mirror or metal) show their own current radiance, split:
  // diffuse + specular (svgf_remodulate's KEEP_UNEXPLAINED).
  bool keep_unexplained = false;
  // converge_still != 0 (with the harm guard): svgf_reproject keeps a still
  // pixel's running mean of its own samples, and svgf_remodulate's guard
  // pulls the output to it within harm_guard standard deviations of it.
  bool converge_still = false;
  // Set: the chain's last pass (svgf_remodulate, or svgf_taa) writes the
  // displayed frame to this scratch buffer (vec4(rgb, 0) fp32, read as texels; add_svgf_buffers adds
  // it) for a pass of the caller's that writes Output (reflect's median; with
  // extra samples, the caller's pass writes kSupersampleDisplay instead and
  // adds supersample_resolve).
  std::string display;
  // Extra samples per pixel (guide-ray supersampling, supersample.hpp): the
  // signals are mixed before their chains and the displayed frame resolved.
  uint32_t extra_samples = 0;
};

// The largest k of SvgfVariant::normal_power (phi_normal's range ends at 1024).
inline constexpr int32_t kMaxNormalPower = 10;
// k when phi_normal == 2^k exactly, k in 0..kMaxNormalPower, else -1.
int32_t normal_power_of(float phi_normal);

// The a-trous step exponent of iteration i of n: step 2^level.
uint32_t step_level(StepOrder order, uint32_t i, uint32_t n);

// The svgf parameter group's part of a variant (iterations, feedback tap,
// TAA) and whether the session declared Emission; signals are the caller's.
SvgfVariant svgf_variant_from(const SessionConfig& config, const Parameters& p);

// Throws std::logic_error naming the first field (or combination) the
// shaders do not implement.
void check_supported(const SvgfVariant& variant);

// The builder, in the graph's order: inputs, then the variant's persistent
// and scratch buffers, then (after any buffers and passes of the caller's
// own, such as svgf-fb's factor) the passes. The caller adds the output
// plane; modulator buffers that are not inputs are the caller's too.
void add_svgf_inputs(GraphSpec& g, const SessionConfig& config, const SvgfVariant& variant);
void add_svgf_buffers(GraphSpec& g, const SvgfVariant& variant);
void add_svgf_passes(GraphSpec& g, const SessionConfig& config, const SvgfVariant& variant);

// The first signal's running mean of a still pixel's samples (vec4(mean, n),
// svgf_reproject) and the M2 of their luminance; empty where the variant
// keeps none.
std::string still_mean_buffer(const SvgfVariant& variant);
std::string still_m2_buffer(const SvgfVariant& variant);

// The whole graph of a variant with nothing of the caller's own (svgf,
// progressive): begin_graph, the variant made from the session's resolved
// parameters, inputs, buffers, the output plane, passes.
GraphSpec svgf_graph(const SessionConfig& config, SvgfVariant (*variant)(const SessionConfig&, const Parameters&));

}  // namespace dn::pipelines
