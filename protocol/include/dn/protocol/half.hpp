// IEEE 754 binary16 <-> binary32 for Format::F16 planes, bit-exact and
// independent of the FPU rounding mode (protocol/src/half.cpp).
#pragma once

#include <cstdint>

namespace dn::protocol {

uint16_t float_to_half(float value);
float half_to_float(uint16_t bits);

}  // namespace dn::protocol
