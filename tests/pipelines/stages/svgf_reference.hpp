// Independent CPU reference of the svgf pipeline in double precision, written
// from the specification in docs/pipelines.md ("svgf in detail") with plain
// loops. Every pass's result is kept for inspection.
#pragma once

#include <cstdint>
#include <vector>

#include "pipelines/pipeline.hpp"

namespace dn::test {

struct SvgfParams {
  double alpha_colour = 0.05;
  double alpha_moments = 0.2;
  double max_history = 32.0;
  int atrous_iterations = 4;
  int feedback_tap = 0;
  double phi_colour = 10.0;
  double phi_normal = 128.0;
  double phi_depth = 1.0;
  double taa_alpha = 0.0;         // > 0: the final TAA blend at moving pixels (pass 5)
  double taa_static_alpha = 0.5;  // > 0: its weight at static pixels (pass 5)
  double harm_guard = 2.0;      // > 0: pull the filtered signals back toward their temporal means (pass 4a)
  double converge_still = 3.0;  // k > 0: still pixels' guard target is their running mean, k of its sigmas (passes 1, 4a)
  int keep_unexplained = 1;     // pixels whose albedo is no reflectance keep their current radiance; split: no-lobe specular (pass 4b)
  double clip_roughness = 0.9;  // > 0: history clipping of the radiance / specular chain (pass 1)
  int variance_of_mean = 1;      // 1: the variance steering the a-trous is the temporal mean's (pass 2)
  int luminance_ramp = 0;        // 1: paper 001 Eq. 8, phi_l times 8 - min(7, length - 1) (pass 3)
  int propagate_variance = 1;    // 0: every a-trous iteration keeps the variance pass's estimate (pass 3)
  // Progressive SVGF (paper 004) switches; their defaults are svgf's.
  int kernel_radius = 2;            // a-trous taps -r..r: 2 the 5x5 B3 spline, 1 the 3x3 {1/4, 1/2, 1/4} (pass 3)
  bool finest_first = false;        // steps 1, 2^(n-1), ..., 4, 2 instead of 1, 2, 4, ... (pass 3)
  int luminance_form = 0;           // 0: phi_colour sqrt(g); 1: sigma_luminance g + epsilon_luminance (pass 3)
  double sigma_luminance = 4.0;     // luminance_form 1
  double epsilon_luminance = 0.05;  // luminance_form 1
  bool spatial_estimate = true;     // false: young pixels' variance from their own moments, no 7x7 (pass 2)
  double luminance_min_age = 0.0;   // no luminance weight where p's history length is below this (pass 3)
  double luminance_ramp_in = 0.0;  // progressive: the weight comes in over this many samples past luminance_min_age
  bool display_lag = false;        // progressive: pass 5's clamp gives way as a still pixel comes of age
};

// The variance of a pixel without data (sample_count: never sampled, nothing
// reprojected), as the device marks it (DN_SVGF_NO_DATA).
inline constexpr double kSvgfNoData = -1.0;

// Session parameters (the svgf and progressive groups, by name) into the
// reference's: each named one replaces the field's current value.
void apply_parameters(SvgfParams& p, const std::vector<pipelines::ParameterValue>& values);

// One frame of inputs, decoded to doubles (NaN/Inf kept as sent); motion in
// pixels towards the previous frame. emission empty when the session has none.
// Split mode: radiance empty, diffuse and specular set; each goes through its
// own chain of the same passes (diffuse demodulated by albedo, specular with
// albedo 1) with its own history, and the output is diffuse x albedo +
// specular + emission.
// svgf-fb: specular_factor holds F_beta per pixel (3 per pixel; empty = 1),
// guarded like albedo; the specular chain is divided by it unless
// specular_lighting (the signal is L_W already, the lighting form), and its
// result is multiplied by it at remodulation. diffuse_lighting: the diffuse
// signal is divided by albedo already.
struct SvgfFrame {
  std::vector<double> radiance, albedo, normal, depth, motion, emission;
  std::vector<double> diffuse, specular;
  std::vector<double> specular_factor;
  std::vector<double> roughness;  // empty: the session has none (then nothing is clipped)
  // Samples taken this frame, 1 per pixel (empty: every pixel sampled). A
  // foreground pixel whose count is not > 0 (NaN: not) keeps its reprojected
  // history unchanged, or has no data without one (progressive).
  std::vector<double> sample_count;
  bool diffuse_lighting = false, specular_lighting = false;
  bool reset = false;
};

class SvgfReference {
 public:
  SvgfReference(int width, int height, SvgfParams params);
  // Returns the Output plane, 3 per pixel.
  std::vector<double> step(const SvgfFrame& frame);

  // Results of the last step, per pass, of the radiance (or, split, diffuse: chain 0) or specular (chain 1) chain.
  const std::vector<double>& temporal_colour(int c = 0) const { return chains_[c].temporal; }  // 3 per pixel
  // 1 per pixel; kSvgfNoData at a pixel without data (also in atrous's .w)
  const std::vector<double>& variance(int c = 0) const { return chains_[c].variance; }
  const std::vector<double>& atrous(int i, int c = 0) const { return chains_[c].atrous[i]; }   // 4 per pixel
  const std::vector<double>& history_length(int c = 0) const { return chains_[c].length; }     // 1 per pixel
  // The remodulated colour before the TAA blend (= the output without TAA), 3 per pixel.
  const std::vector<double>& remodulated() const { return remodulated_; }

 private:
  // One signal's history (previous frame: demodulated colour, length,
  // moments) and the per-pass results of the last step.
  struct Chain {
    std::vector<double> colour, length, m1, m2;
    std::vector<double> still_mean, still_n;  // converge_still: a still pixel's running mean of its samples (3 + 1 per pixel)
    std::vector<double> still_m2;             // and the M2 of their luminance
    std::vector<float> change;                // its change test: running mean, M2, recent mean of the 3x3 box luminance
    std::vector<double> temporal, variance;
    std::vector<std::vector<double>> atrous;
  };
  int w_, h_;
  SvgfParams p_;
  bool has_history_ = false;
  Chain chains_[2];
  // Geometry history (previous frame): depth (0 = none), normal.
  std::vector<double> z_, n_;
  // converge_still with emission: a still pixel's running mean of its
  // emission (3 per pixel), its samples, the M2 of their luminance and
  // whether its change test failed last frame.
  std::vector<double> emission_mean_, emission_n_, emission_m2_;
  std::vector<bool> emission_suspect_;
  // TAA history: the previous final output, 3 per pixel.
  std::vector<double> taa_;
  // display_lag's state per pixel (pass 5).
  std::vector<double> lag_;
  std::vector<double> remodulated_;
};

}  // namespace dn::test
