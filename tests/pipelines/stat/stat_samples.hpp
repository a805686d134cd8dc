// Synthetic per-pixel samples for the stat tests: exponential around a mean
// (skewed, like path tracing), with the statistics dnrender computes.
#pragma once

#include <cmath>
#include <random>

#include "online_stats.hpp"
#include "stat_reference.hpp"

namespace dn::test {

// Channel c of pixel i of f from `count` exponential samples of mean `mean`
// drawn from rng: the radiance their mean, the statistics over sample /
// divisor (1: over radiance; the guarded albedo: demodulated, as dnrender
// --stats-demodulated).
inline void put_exponential_samples(StatFrame& f, int i, int c, int count, float mean, float divisor,
                                    std::mt19937& rng) {
  render::OnlineStats statistics, radiance;
  for (int k = 0; k < count; ++k) {
    const double u = (static_cast<double>(rng()) + 0.5) / 4294967296.0;
    const float sample = static_cast<float>(-std::log(u)) * mean;
    statistics.add(sample / divisor);
    radiance.add(sample);
  }
  const int k = 3 * i + c;
  f.radiance[k] = radiance.raw_mean;
  f.mean[k] = statistics.mean;
  f.m2[k] = statistics.m2;
  f.m3[k] = statistics.m3;
}

}  // namespace dn::test
