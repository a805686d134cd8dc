#version 450
// supersample_mix: paper 001 Eq. 7, u(g) <- (u(g) + sum of the extra samples
// assigned to g) / (1 + their number), per colour channel, on the signal as
// sent (before demodulation, as the paper mixes "unfiltered sample energy").
// The samples that can be assigned to guide g lie in g's 3x3 pixels. Values
// are sanitized first (NaN, Inf, negatives and values above the radiance bound as 0), as every signal is.
// One invocation per pixel.
//
// Resources: supersample_mix.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "reproject.glsl"
#include "pass.glsl"
#include "generated/passes/supersample_mix.pass"

#include "supersample.glsl"

vec3 sanitized(vec3 c) { return dn_sanitize_radiance(c); }

#define DN_MIX(j, buf)                                                                \
  if (SAMPLES >= j && dn_sample_code(word, j) == want) {                              \
    sum += sanitized(DN_LOAD3(buf, qi));                          \
    count += 1.0;                                                                     \
  }

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  vec3 sum = sanitized(DN_LOAD3(signal, p));
  float count = 1.0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      ivec2 q = pos + ivec2(dx, dy);
      if (!dn_inside(q, frame.size.xy)) continue;
      uint qi = uint(q.y) * frame.size.x + uint(q.x);
      uint word = assignment_at(qi);
      uint want = dn_sample_code_of(-ivec2(dx, dy));  // q's sample belongs to p
      DN_MIX(1u, signal_1)
      DN_MIX(2u, signal_2)
      DN_MIX(3u, signal_3)
    }
  vec3 m = sum / count;
  mixed.data[3u * p] = floatBitsToUint(m.x);
  mixed.data[3u * p + 1u] = floatBitsToUint(m.y);
  mixed.data[3u * p + 2u] = floatBitsToUint(m.z);
}
