// Independent CPU reference of the stat pipeline, written from
// docs/pipelines.md ("stat") with plain loops. The per-pixel inputs of the
// test (theta, variance) and the membership decisions are made in single
// precision in the device's operation order, so rounding cannot flip a
// decision between the two; the weighted sums are in double.
#pragma once

#include <vector>

namespace dn::test {

// Defaults: the pipeline's (falloff 4, alpha 0.05); paper() gives paper 003's.
struct StatParams {
  double alpha = 0.05;
  int radius = 20;
  double sigma_spatial = 10.0, sigma_albedo = 0.02, sigma_normal = 0.1;
  double variance_floor = 0.0;
  bool asymmetric = false;
  bool base_only = false;  // every tap with statistics is a member (the t -> infinity limit)
  // A member's weight times (1 - r)^falloff, r the largest channel's share of
  // the test's bound (0: all or nothing).
  double falloff = 4.0;
  // The statistics are demodulated: the filter averages the demodulated
  // means from the moments and multiplies by p's modulation.
  bool demodulated = false;
  // stat-temporal's pool_single: a pixel with samples but fewer than 2 is
  // tested as its own mean with, per channel, the second smallest sample
  // variance of the merged statistics of the 2x2 quadrants of its 3x3 window
  // that hold it (fp32 merges in the device's row order).
  bool pool_single = false;
  // stat-temporal's spatial_shrink_from N: a pixel that is not moving, with
  // n > N samples of its own, has the spatial sigma sigma_spatial sqrt(N / n)
  // (fp32) and its disc min(radius, ceil(3 sigma)).
  double spatial_shrink_from = 0.0;

  // Paper 003's setting: alpha 0.005, all-or-nothing membership.
  static StatParams paper() {
    StatParams p;
    p.alpha = 0.005;
    p.falloff = 0.0;
    return p;
  }
};

// One frame's planes as floats: radiance, albedo, normal, mean, m2, m3 3 per
// pixel; count 1 per pixel.
struct StatFrame {
  int width = 0, height = 0;
  std::vector<float> radiance, albedo, normal, count, mean, m2, m3;
};

struct StatPrepared {
  std::vector<float> theta;     // 4 per pixel: rgb, n (0: no statistics)
  std::vector<float> variance;  // 3 per pixel
  std::vector<char> moving;     // per pixel (stat-temporal): p's neighbours are tested by Eq. 14; empty: none
  std::vector<char> kept;       // per pixel (stat-temporal): p shows its own mean, gathering nothing; empty: none
};

struct StatResult {
  std::vector<double> output;  // 3 per pixel
  std::vector<int> members;    // per pixel: members of its disc besides itself
  std::vector<int> rejected;   // per pixel: taps with statistics the test rejected
};

StatPrepared stat_prepare(const StatFrame& f, const StatParams& p);
// t_squared: entry k holds t^2 for nu = k + 1 (the pipeline's table at
// alpha); still_t_squared the same at stat-temporal's still_alpha, for a pair
// of still pixels with statistics of their own (empty: t_squared).
StatResult stat_filter(const StatFrame& f, const StatPrepared& prep, const StatParams& p,
                       const std::vector<float>& t_squared, const std::vector<float>& still_t_squared = {});
// An albedo component as demodulation uses it: below 1e-3 (fp32) or not
// finite, 1 (docs/protocol.md §7.7).
// Whether a pixel's statistics (count, and 3 means, M2, M3) are data: finite,
// 0 < n <= 2^24, |mean| <= Y, M2 <= n Y^2, |M3| <= n Y^3 with Y = 2 sqrt(1e12) - 2
// (docs/pipelines.md "Guide sanitization").
bool statistics_usable(float count, const float* mean, const float* m2, const float* m3);
double guarded_albedo(float a);
// The mean of the samples from their Box-Cox moments, (mean / 2 + 1)^2 + M2 / (4 n).
double raw_from_moments(double n, double mean, double m2);
// radiance / demodulated mean, or the guarded albedo where either is 0.
double modulation(double radiance, double demodulated, float albedo);
// The membership decision for one channel pair (exposed for the symmetry test).
bool stat_member(float theta_p, float theta_q, float t2, float var_p, float var_q, bool asymmetric);

}  // namespace dn::test
