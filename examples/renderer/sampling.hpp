// Random numbers and the warps the integrator needs. Every random stream is a
// pure function of (seed, frame, pixel), so a frame renders to the same bits
// whatever the thread count or tile order.
#pragma once

#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>

namespace dn::render {

inline constexpr float kPi = 3.14159265358979f;

inline uint32_t hash_u32(uint32_t h) {
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return h;
}

inline uint32_t hash_combine(uint32_t a, uint32_t b) { return hash_u32(a ^ (b + 0x9E3779B9u + (a << 6) + (a >> 2))); }

// Uniform in [0, 1) from 24 hash bits.
inline float to_unit_float(uint32_t h) { return static_cast<float>(h >> 8) * (1.0f / 16777216.0f); }

// PCG32 (O'Neill): small state, good enough statistics for path tracing.
class Rng {
 public:
  Rng(uint32_t seed, uint32_t frame, uint32_t pixel) {
    state_ = 0;
    inc_ = (uint64_t{hash_combine(seed, 0x51ED270Bu)} << 1) | 1u;
    next_u32();
    state_ += uint64_t{hash_combine(hash_combine(seed, frame), pixel)} << 16 | pixel;
    next_u32();
  }
  uint32_t next_u32() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ull + inc_;
    const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
  }
  float next() { return to_unit_float(next_u32()); }
  glm::vec2 next2() {
    const float a = next();
    return {a, next()};
  }

 private:
  uint64_t state_, inc_;
};

// Orthonormal basis around a unit normal (Duff et al. 2017, branchless).
struct Frame {
  glm::vec3 t, b, n;
  explicit Frame(const glm::vec3& normal) : n(normal) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float bb = n.x * n.y * a;
    t = glm::vec3(1.0f + sign * n.x * n.x * a, sign * bb, -sign * n.x);
    b = glm::vec3(bb, sign + n.y * n.y * a, -n.y);
  }
  glm::vec3 to_local(const glm::vec3& v) const { return {glm::dot(v, t), glm::dot(v, b), glm::dot(v, n)}; }
  glm::vec3 to_world(const glm::vec3& v) const { return v.x * t + v.y * b + v.z * n; }
};

inline glm::vec3 sample_cosine_hemisphere(glm::vec2 u) {
  const float r = std::sqrt(u.x);
  const float phi = 2.0f * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - u.x))};
}

// Direction inside a cone of half-angle acos(cos_max) around +z, uniform in solid angle.
inline glm::vec3 sample_cone(glm::vec2 u, float cos_max) {
  const float cos_t = 1.0f - u.x * (1.0f - cos_max);
  const float sin_t = std::sqrt(std::max(0.0f, 1.0f - cos_t * cos_t));
  const float phi = 2.0f * kPi * u.y;
  return {sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t};
}

// Power heuristic (beta = 2) weight of technique a against b.
inline float power_heuristic(float pdf_a, float pdf_b) {
  const float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  return a + b > 0.0f ? a / (a + b) : 0.0f;
}

inline float luminance(const glm::vec3& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

// Halton radical inverse, for the per-frame sub-pixel camera jitter.
inline float radical_inverse(uint32_t i, uint32_t base) {
  float f = 1.0f, r = 0.0f;
  while (i > 0) {
    f /= static_cast<float>(base);
    r += f * static_cast<float>(i % base);
    i /= base;
  }
  return r;
}

}  // namespace dn::render
