// Independent CPU reference of the accumulate pipeline in double precision,
// written from the specification in docs/pipelines.md with plain loops.
#pragma once

#include <cstdint>
#include <vector>

namespace dn::test {

struct AccumulateParams {
  double alpha_min = 0.05;
  double max_history = 32.0;
  double depth_tolerance = 0.1;
  double normal_threshold = 0.9;
};

// One frame of inputs, already decoded to doubles (NaN/Inf kept as sent).
// motion is in pixels pointing to the previous frame (the caller converts
// other conventions the way the protocol defines them).
struct ReferenceFrame {
  std::vector<double> radiance;  // 3 per pixel
  std::vector<double> normal;    // 3 per pixel
  std::vector<double> depth;     // 1 per pixel
  std::vector<double> motion;    // 2 per pixel, pixels to previous
  bool reset = false;
};

class AccumulateReference {
 public:
  AccumulateReference(int width, int height, AccumulateParams params);
  // Returns the output radiance, 3 per pixel.
  std::vector<double> step(const ReferenceFrame& frame);
  // History after the last step (for inspection): rgb + length, normal + depth.
  const std::vector<double>& colour_history() const { return colour_; }
  const std::vector<double>& geometry_history() const { return geometry_; }

 private:
  int w_, h_;
  AccumulateParams p_;
  bool has_history_ = false;
  std::vector<double> colour_;    // 4 per pixel
  std::vector<double> geometry_;  // 4 per pixel
};

}  // namespace dn::test
