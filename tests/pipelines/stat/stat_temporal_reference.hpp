// Independent CPU reference of stat-temporal's stat_temporal pass, written
// from docs/pipelines.md ("stat-temporal") with plain loops in double: the
// accumulators a frame leaves, given the previous ones. (stat_prepare and
// stat_filter then run on them as in stat_reference.hpp.)
#pragma once

#include <vector>

#include "stat_reference.hpp"

namespace dn::test {

struct StatAccumulator {
  double n = 0.0;
  double mean[3] = {0, 0, 0}, m2[3] = {0, 0, 0}, m3[3] = {0, 0, 0}, raw[3] = {0, 0, 0};
};

// P0b: the accumulator of the union of a's and b's samples.
StatAccumulator stat_merge(const StatAccumulator& a, const StatAccumulator& b);
StatAccumulator stat_scale(StatAccumulator a, double f);

struct StatTemporalState {
  std::vector<StatAccumulator> acc;  // per pixel
  std::vector<float> depth;          // per pixel, 0: no history
  std::vector<float> normal;         // 3 per pixel
  std::vector<int> suspect;          // per pixel: 1 where the last test failed without a rejection
};

struct StatTemporalFrame {
  StatFrame stats;
  std::vector<float> depth;   // 1 per pixel
  std::vector<float> motion;  // 2 per pixel, pixels to the previous frame
  bool reset = false;
};

struct StatTemporalResult {
  StatTemporalState state;
  std::vector<int> rejected;  // per pixel: 1 where a reprojected history failed the test
};

// previous: empty vectors for the first frame. t_squared as in stat_filter.
StatTemporalResult stat_temporal(const StatTemporalFrame& f, const StatTemporalState& previous, double fading,
                                 const std::vector<float>& t_squared);

}  // namespace dn::test
