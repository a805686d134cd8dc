// Independent CPU reference of the svgf pipeline in double precision, written
// from the specification in docs/pipelines.md ("svgf in detail") with plain
// loops. Every pass's result is kept for inspection.
#pragma once

#include <cstdint>
#include <vector>

namespace dn::test {

struct SvgfParams {
  double alpha_colour = 0.05;
  double alpha_moments = 0.2;
  double max_history = 32.0;
  int atrous_iterations = 4;
  int feedback_tap = 1;
  double phi_colour = 10.0;
  double phi_normal = 128.0;
  double phi_depth = 1.0;
};

// One frame of inputs, decoded to doubles (NaN/Inf kept as sent); motion in
// pixels towards the previous frame. emission empty when the session has none.
struct SvgfFrame {
  std::vector<double> radiance, albedo, normal, depth, motion, emission;
  bool reset = false;
};

class SvgfReference {
 public:
  SvgfReference(int width, int height, SvgfParams params);
  // Returns the Output plane, 3 per pixel.
  std::vector<double> step(const SvgfFrame& frame);

  // Results of the last step, per pass.
  const std::vector<double>& temporal_colour() const { return temporal_; }    // 3 per pixel (demodulated)
  const std::vector<double>& variance() const { return variance_; }           // 1 per pixel
  const std::vector<double>& atrous(int i) const { return atrous_[i]; }       // 4 per pixel: rgb, variance
  const std::vector<double>& history_length() const { return length_; }       // 1 per pixel

 private:
  int w_, h_;
  SvgfParams p_;
  bool has_history_ = false;
  // History (previous frame): demodulated colour, length, moments, depth (0 = none), normal.
  std::vector<double> colour_, length_, m1_, m2_, z_, n_;
  std::vector<double> temporal_, variance_;
  std::vector<std::vector<double>> atrous_;
};

}  // namespace dn::test
