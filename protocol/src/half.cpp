// IEEE 754 binary16 <-> binary32 (dn/protocol/half.hpp).
#include <bit>

#include "dn/protocol/half.hpp"

namespace dn::protocol {

uint16_t float_to_half(float value) {
  const uint32_t x = std::bit_cast<uint32_t>(value);
  const uint16_t sign = static_cast<uint16_t>((x >> 16) & 0x8000u);
  const uint32_t a = x & 0x7FFFFFFFu;

  if (a >= 0x7F800000u) {                 // Inf or NaN
    if (a == 0x7F800000u) return sign | 0x7C00u;
    uint32_t mant = (a >> 13) & 0x3FFu;   // keep the top payload bits (quiet bit included)
    if (mant == 0) mant = 0x200u;         // payload only in the low bits: stay NaN, quiet
    return static_cast<uint16_t>(sign | 0x7C00u | mant);
  }
  if (a >= 0x477FF000u) return sign | 0x7C00u;  // >= 65520 rounds (to even) past 65504: Inf

  if (a >= 0x38800000u) {  // normal half: |v| >= 2^-14
    const uint32_t rebased = a - (112u << 23);  // exponent bias 127 -> 15
    const uint32_t rounded = rebased + 0xFFFu + ((rebased >> 13) & 1u);  // nearest, ties to even
    return static_cast<uint16_t>(sign | (rounded >> 13));
  }

  // Subnormal half (or zero): value = m * 2^-24.
  const uint32_t exp = a >> 23;
  if (exp < 102) return sign;  // < 2^-25: rounds to zero (2^-25 itself is handled below)
  const uint32_t mant = (a & 0x7FFFFFu) | 0x800000u;
  const uint32_t shift = 126 - exp;  // 14 .. 24
  uint32_t m = mant >> shift;
  const uint32_t rem = mant & ((1u << shift) - 1u);
  const uint32_t halfway = 1u << (shift - 1);
  if (rem > halfway || (rem == halfway && (m & 1u))) ++m;  // may carry into the smallest normal: correct
  return static_cast<uint16_t>(sign | m);
}

float half_to_float(uint16_t bits) {
  const uint32_t sign = static_cast<uint32_t>(bits & 0x8000u) << 16;
  const uint32_t exp = (bits >> 10) & 0x1Fu;
  uint32_t mant = bits & 0x3FFu;
  uint32_t out;
  if (exp == 0x1F) {
    out = sign | 0x7F800000u | (mant << 13);  // Inf, or NaN with its payload
  } else if (exp != 0) {
    out = sign | ((exp + 112u) << 23) | (mant << 13);
  } else if (mant == 0) {
    out = sign;
  } else {  // subnormal: normalise
    uint32_t e = 113;  // exponent of 2^-14 in binary32 bias
    while ((mant & 0x400u) == 0) {
      mant <<= 1;
      --e;
    }
    out = sign | (e << 23) | ((mant & 0x3FFu) << 13);
  }
  return std::bit_cast<float>(out);
}

}  // namespace dn::protocol
