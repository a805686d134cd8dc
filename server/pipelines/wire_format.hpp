// The boundary between a client's wire formats and the pipelines' internal
// layout: every plane lives on the device as fp32, so no pass is specialised
// by the format a client sends or wants back. An fp16 input plane is widened
// as it is copied into its upload buffer (exact: every half is a float); an
// fp16 output is narrowed as it is read back, rounding to nearest even and
// saturating finite values at the largest half (65504) instead of making Inf.
#pragma once

#include <cstddef>
#include <cstdint>

namespace dn::pipelines {

// dst[i] = the fp32 value of the little-endian half src[i], for i < count.
void widen_halves(const uint8_t* src, size_t count, float* dst);

// dst[i] = src[i] as a little-endian half: nearest even, finite values beyond
// +-65504 saturate to it; NaN stays NaN and +-Inf stays +-Inf.
void narrow_to_halves(const float* src, size_t count, uint8_t* dst);

}  // namespace dn::pipelines
