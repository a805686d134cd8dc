// The SVGF chain's stages, each a function over the named buffers and the
// switches of its own struct (an empty name: none). svgf_chain.cpp fills
// them from an SvgfVariant and calls them in order: per signal
// add_clip_prefilter (a clipped one) and add_reprojection, then
// add_variance, add_atrous, add_remodulate and add_taa, between the
// supersampling stages of supersample.hpp.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "pipelines/graph.hpp"

namespace dn::pipelines::svgf {

// One signal's buffers through the chain.
struct SignalChain {
  std::string suffix;           // of its passes' names ("" with one signal, "_diffuse", ...)
  std::string signal;           // what it filters: its plane, or supersample_mix's result
  std::string modulator;        // divided by before filtering, multiplied by after
  bool client_divided = false;  // the client divided the signal already: multiplied only
  std::string emission;         // the signal includes this emission: filtered without it
  std::string colour_history, aux_history;
  std::string guide, temporal;  // its reprojection's guide (maybe the first signal's) and moments
  std::string illum, other;     // the a-trous ping-pong; illum holds the reprojected signal
  std::string depth, normal;    // its edge-stopping and history-test features
  std::string motion;
  std::string reflection_motion;  // reprojected with this instead of motion (reflect_motion's)
  // converge_still: a still pixel's running mean, the M2 of its luminance and its change test.
  std::string still_mean, still_m2, still_change;

  bool demodulates() const { return !modulator.empty() && !client_divided; }
};

// svgf_clip_prefilter's three passes: the demodulated current signal, then
// its 7x7 Gaussian by rows and columns, the box history clipping reads.
struct ClipStage {
  std::string suffix;
  std::string signal, depth;
  std::string modulator;  // the signal is divided by it (DEMODULATE)
  std::string emission;   // subtracted from the signal
  std::string current, partial, neighbourhood;
};
void add_clip_prefilter(GraphSpec& g, const ClipStage& stage);

// What a clipped reprojection reads: the clip stage's box and current signal,
// and the roughness below whose threshold it clips.
struct ClipBox {
  std::string neighbourhood, current, roughness;
};

// svgf_reproject: a signal's temporal colour (into its illum), moments and length.
struct ReprojectStage {
  SignalChain signal;
  bool write_guide = true;      // false: it reads the first signal's
  bool read_history = true;     // false: filtered from the current frame alone
  bool specular_alpha = false;  // the blend's floor is alpha_specular (group specular)
  std::string surface_still;    // its still mean goes on while this one (its surface's) does
  std::optional<ClipBox> clip;
  std::string validity_mask;    // unsampled pixels keep their history (MASKED)
};
void add_reprojection(GraphSpec& g, const ReprojectStage& stage);

// svgf_variance: every signal's variance and history write-back in one pass.
struct VarianceStage {
  std::vector<SignalChain> signals;  // one or two
  bool spatial_estimate = true;      // a young pixel's variance from its 7x7 neighbourhood
};
void add_variance(GraphSpec& g, const VarianceStage& stage);

// svgf_atrous: the iterations, every signal in the same passes.
struct AtrousStage {
  std::vector<SignalChain> signals;  // one or two
  std::vector<uint32_t> levels;      // one per iteration: its step is 2^level
  uint32_t feedback_tap = 0;         // the iteration whose output becomes the colour histories
  uint32_t kernel_radius = 2;        // 2: the 5x5 B3 kernel, 1: the 3x3
  bool luminance_variance = false;   // paper 004's variance form of the luminance weight
  bool age_gated_luminance = false;  // no luminance weight for young pixels
  bool class_edges = false;          // the last signal takes no tap across reflection classes
  bool luminance_ramp = false;
  int32_t normal_power = -1;         // SvgfVariant::normal_power
  bool display_fill = false;         // the last iteration fills pixels without data for the display
  std::string bandwidth;             // the last signal's per-pixel Gaussian on the tap offsets
  std::string validity_mask;         // the feedback writes sampled pixels only (MASKED)
  // Per signal: after the first iteration the ping-pong partner instead of
  // illum, so illum keeps the variance pass's output for the harm guard.
  std::vector<std::string> guard_partners;
};
// Returns the buffer holding each signal's final illumination.
std::vector<std::string> add_atrous(GraphSpec& g, const SessionConfig& config, const AtrousStage& stage);

// Where the chain's last pass writes the displayed frame: a result plane, or
// a display scratch the caller's pass reads as texels (TO_DISPLAY).
struct FrameTarget {
  std::string buffer;
  bool display = false;
};
// svgf_remodulate's output for svgf_taa, and svgf_taa's history.
struct TaaBuffers {
  std::string current, previous, history;
};

// svgf_remodulate: the filtered signals times their modulators, and the guards.
struct RemodulateStage {
  std::vector<SignalChain> signals;    // their modulators, histories and reprojected illum
  std::vector<std::string> filtered;   // each signal's a-trous result
  std::string emission;                // added back
  std::string emission_still, emission_test;  // a still pixel's emission mean and its test
  std::string motion, depth;           // read by the TAA, keep_raw and emission_still
  std::optional<TaaBuffers> taa;       // writes these for add_taa instead of the frame
  bool display_lag = false;            // with taa: SvgfVariant::display_lag
  FrameTarget target;                  // without taa
  // keep_unexplained: the planes as sent, one per signal, shown where the
  // first albedo is not a reflectance; with validity_mask at sampled pixels only.
  std::vector<std::string> keep_raw;
  std::string validity_mask;
  // Pulls each signal toward its own temporal mean (its illum), with
  // converge_still (its still_mean) toward a still pixel's running mean.
  bool harm_guard = false;
  bool specular_alpha = false;         // the second signal's floor is alpha_specular (group specular)
};
void add_remodulate(GraphSpec& g, const RemodulateStage& stage);

// svgf_taa: the final blend of svgf_remodulate's current and reprojected previous frame.
struct TaaStage {
  TaaBuffers buffers;
  std::string depth;
  bool display_lag = false;
  FrameTarget target;
};
void add_taa(GraphSpec& g, const TaaStage& stage);

// Binding helpers the stages share (svgf_stages.cpp).
// The sample_count binding as a pass's validity mask (MASKED).
void bind_validity_mask(PassSpec& pass, const std::string& mask);
// The joint passes' second-signal geometry (svgf_joint.glsl): its temporal
// and, when it is not the first's, its own guide (SECOND_GUIDE).
void bind_second_geometry(PassSpec& pass, const SignalChain& first, const SignalChain& second);
void bind_target(PassSpec& pass, const FrameTarget& target);

}  // namespace dn::pipelines::svgf
