// Independent CPU reference of the image pipeline in double precision,
// written from docs/pipelines.md ("image") with plain loops.
#pragma once

#include <vector>

namespace dn::test {

struct ImageParams {
  int iterations = 5;
  double phi_luminance = 4.0;
  double phi_normal = 128.0;
  double phi_depth = 0.05;
  double phi_albedo = 0.1;
  double noise_cap = 1.0;
  double harm_guard = 3.0;
  bool decorrelated_noise = false;  // noise_estimate 1
};

// One frame's planes decoded to doubles (NaN and Inf kept as sent); an
// empty guide is one the session does not have.
struct ImageFrame {
  std::vector<double> radiance;  // 3 per pixel
  std::vector<double> albedo;    // 3 per pixel, or empty
  std::vector<double> normal;    // 3 per pixel, or empty
  std::vector<double> depth;     // 1 per pixel, or empty
};

// The output radiance, 3 per pixel.
std::vector<double> image_reference(int width, int height, const ImageFrame& frame, const ImageParams& params);

}  // namespace dn::test
