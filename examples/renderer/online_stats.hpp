// Per-pixel online statistics of paper 003 (Sakai et al. 2024), Alg. 1:
// Welford/Meng updates of the mean and the sums M2, M3 of Box-Cox (lambda = 1/2)
// transformed samples, plus the mean of the raw samples; merge() combines two
// partial accumulators exactly.
#pragma once

#include <cmath>

namespace dn::render {

// A sample as the statistics take it (docs/protocol.md §7.7): NaN, +-inf and
// negative values count as 0, as StatMC does.
inline float sanitize_sample(float x) { return std::isfinite(x) && x > 0.0f ? x : 0.0f; }

// Box-Cox with lambda = 1/2: (x^0.5 - 1) / 0.5. Negative input is clamped to 0.
inline float box_cox_half(float x) { return 2.0f * std::sqrt(x > 0.0f ? x : 0.0f) - 2.0f; }

struct OnlineStats {
  float n = 0.0f;
  float mean = 0.0f, m2 = 0.0f, m3 = 0.0f;  // of the transformed samples; m2, m3 are sums (central moment = m/n)
  float raw_mean = 0.0f;

  void add(float x) {
    n += 1.0f;
    raw_mean += (x - raw_mean) / n;
    const float delta = box_cox_half(x) - mean;
    const float delta_n = delta / n;
    mean += delta_n;
    // M3 first: this classical form (Pebay 2008) uses the M2 of the previous n
    // and adds delta^3 (n-1)(n-2)/n^2 - 3 delta_n M2. The paper's Alg. 1 writes
    // the same update with the already updated M2; either order alone is
    // exact, mixing them is not (tests/renderer/statistics_test.cpp).
    const float term = delta * delta_n * (n - 1.0f);
    m3 += term * delta_n * (n - 2.0f) - 3.0f * delta_n * m2;
    m2 += term;
  }

  // Folds accumulator b into this one, as if b's samples had been add()ed
  // here: per-frame or per-thread partials and temporal reuse need it
  // (notes A.2 P0b; Chan et al. 1979, Pebay 2008). The formulas are exact for
  // any split. An empty side contributes nothing and is never divided by.
  void merge(const OnlineStats& b) {
    if (b.n == 0.0f) return;
    if (n == 0.0f) {
      *this = b;
      return;
    }
    const float na = n, nb = b.n, nt = na + nb;
    const float delta = b.mean - mean;
    const float share_b = nb / nt;
    const float nab = na * share_b;  // nA nB / n, without forming nA nB
    // M3 first: its cross term needs both M2s as they were before the merge.
    m3 += b.m3 + delta * delta * delta * nab * (na - nb) / nt + 3.0f * delta * (na * b.m2 - nb * m2) / nt;
    m2 += b.m2 + delta * delta * nab;
    mean += delta * share_b;
    raw_mean += (b.raw_mean - raw_mean) * share_b;  // the weighted mean of the two
    n = nt;
  }
};

}  // namespace dn::render
