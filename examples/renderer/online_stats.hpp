// Per-pixel online statistics of paper 003 (Sakai et al. 2024), Alg. 1:
// Welford/Meng updates of the mean and the sums M2, M3 of Box-Cox (lambda = 1/2)
// transformed samples, plus the mean of the raw samples.
#pragma once

#include <cmath>

namespace dn::render {

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
    // M3 first: it uses the M2 of the previous n. The exact one-sample update
    // (Pebay 2008; Meng 2015) adds delta^3 (n-1)(n-2)/n^2; the paper's printed
    // delta (delta^2 - (delta/n)^2) does not vanish for two samples, where M3 must.
    const float term = delta * delta_n * (n - 1.0f);
    m3 += term * delta_n * (n - 2.0f) - 3.0f * delta_n * m2;
    m2 += term;
  }
};

}  // namespace dn::render
