#include "pipelines/wire_format.hpp"

#include "dn/protocol/half.hpp"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define DN_HAVE_X86 1
#endif

namespace dn::pipelines {
namespace {

constexpr float kHalfMax = 65504.0f;

uint16_t load_half(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }

void widen_scalar(const uint8_t* src, size_t count, float* dst) {
  for (size_t i = 0; i < count; ++i) dst[i] = protocol::half_to_float(load_half(src + 2 * i));
}

float saturate_half(float x) {
  if (!(x == x) || x == __builtin_inff() || x == -__builtin_inff()) return x;
  return x > kHalfMax ? kHalfMax : x < -kHalfMax ? -kHalfMax : x;
}

void narrow_scalar(const float* src, size_t count, uint8_t* dst) {
  for (size_t i = 0; i < count; ++i) {
    const uint16_t h = protocol::float_to_half(saturate_half(src[i]));
    dst[2 * i] = static_cast<uint8_t>(h);
    dst[2 * i + 1] = static_cast<uint8_t>(h >> 8);
  }
}

#ifdef DN_HAVE_X86
// The F16C instructions convert eight values at once (every x86-64 CPU since
// 2012 has them; the scalar path serves the rest and the tail).
__attribute__((target("avx,f16c"))) void widen_f16c(const uint8_t* src, size_t count, float* dst) {
  size_t i = 0;
  for (; i + 8 <= count; i += 8)
    _mm256_storeu_ps(dst + i, _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(src + 2 * i))));
  widen_scalar(src + 2 * i, count - i, dst + i);
}

__attribute__((target("avx,f16c"))) void narrow_f16c(const float* src, size_t count, uint8_t* dst) {
  const __m256 max = _mm256_set1_ps(kHalfMax), min = _mm256_set1_ps(-kHalfMax);
  const __m256 inf = _mm256_set1_ps(__builtin_inff());
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  size_t i = 0;
  for (; i + 8 <= count; i += 8) {
    const __m256 x = _mm256_loadu_ps(src + i);
    // min/max return their second operand when either is NaN: NaN passes through.
    const __m256 clamped = _mm256_max_ps(min, _mm256_min_ps(max, x));
    const __m256 is_inf = _mm256_cmp_ps(_mm256_and_ps(x, abs_mask), inf, _CMP_EQ_OQ);
    const __m256 v = _mm256_blendv_ps(clamped, x, is_inf);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + 2 * i), _mm256_cvtps_ph(v, _MM_FROUND_TO_NEAREST_INT));
  }
  narrow_scalar(src + i, count - i, dst + 2 * i);
}

bool has_f16c() {
  static const bool yes = __builtin_cpu_supports("avx") && __builtin_cpu_supports("f16c");
  return yes;
}
#endif

}  // namespace

void widen_halves(const uint8_t* src, size_t count, float* dst) {
#ifdef DN_HAVE_X86
  if (has_f16c()) return widen_f16c(src, count, dst);
#endif
  widen_scalar(src, count, dst);
}

void narrow_to_halves(const float* src, size_t count, uint8_t* dst) {
#ifdef DN_HAVE_X86
  if (has_f16c()) return narrow_f16c(src, count, dst);
#endif
  narrow_scalar(src, count, dst);
}

}  // namespace dn::pipelines
