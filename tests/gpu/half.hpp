// Independent IEEE 754 binary16 conversions for the tests (round to nearest
// even, overflow to infinity, NaN stays NaN, subnormals exact).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

namespace dn::test {

inline uint16_t to_half(float value) {
  uint32_t x;
  std::memcpy(&x, &value, 4);
  const uint16_t sign = static_cast<uint16_t>((x >> 16) & 0x8000u);
  const uint32_t abs = x & 0x7fffffffu;
  if (abs >= 0x7f800000u) return sign | (abs > 0x7f800000u ? 0x7e00u : 0x7c00u);  // NaN / Inf
  // Work on the exact value: |value| = m * 2^e with a 24-bit m.
  const double a = std::fabs(static_cast<double>(value));
  if (a >= 65520.0) return sign | 0x7c00u;  // rounds to infinity
  // Scale to units of the half ulp at this magnitude, round to nearest even.
  int exp;
  std::frexp(a, &exp);  // a = f * 2^exp, f in [0.5, 1)
  int e = exp - 1;      // a in [2^e, 2^(e+1))
  if (e < -14) e = -14; // subnormal range shares the ulp 2^-24
  const double ulp = std::ldexp(1.0, e - 10);
  const double q = a / ulp;  // exact (power-of-two scaling)
  double r = std::nearbyint(q);  // default rounding mode: to nearest even
  uint32_t mant = static_cast<uint32_t>(r);
  // mant in [0, 2048]; 2048 means it rounded up to the next binade
  uint32_t biased = static_cast<uint32_t>(e + 15);
  if (mant >= 2048) {
    mant >>= 1;
    ++biased;
  }
  if (mant < 1024) return sign | static_cast<uint16_t>(mant);  // subnormal (or zero): e == -14
  if (biased >= 31) return sign | 0x7c00u;
  return sign | static_cast<uint16_t>((biased << 10) | (mant & 0x3ffu));
}

inline float from_half(uint16_t h) {
  const uint32_t sign = (h & 0x8000u) ? 1u : 0u;
  const uint32_t exp = (h >> 10) & 0x1fu;
  const uint32_t mant = h & 0x3ffu;
  double v;
  if (exp == 0) {
    v = std::ldexp(static_cast<double>(mant), -24);
  } else if (exp == 31) {
    v = mant ? std::nan("") : INFINITY;
  } else {
    v = std::ldexp(static_cast<double>(mant | 0x400u), static_cast<int>(exp) - 25);
  }
  return static_cast<float>(sign ? -v : v);
}

}  // namespace dn::test
