#version 450
// reflect_median (reflect, last pass): paper 001 §6's firefly suppression,
// a 3x3 median of the displayed frame at foreground pixels whose 3x3
// foreground window is all of reflection class none (a diffuse or rough
// surface away from mirror and glossy pixels, whose highlights and edges a
// median would cut): per channel, the median of the window's filtered light
// (colour minus emission; the value of rank count / 2), plus the pixel's own
// emission (a small light is not a firefly). Per channel, not the
// luminance-ranked vector median: that one jumps to another pixel's colour
// when two luminances swap order, so fp rounding upstream changed the output
// by up to 0.6 % (scene 6, scale test), where a scalar median moves only as
// much as its inputs. It reads the chain's displayed frame and writes only
// Output: no history is touched.
// docs/pipelines.md "reflect".
// One invocation per pixel pair.
//
// Resources: passes/reflect_median.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "luminance.glsl"
#include "reproject.glsl"
#include "pass.glsl"
#include "passes/reflect_median.pass"

#include "reflect.glsl"

vec3 emitted(uint p) { return HAS_EMISSION ? dn_sanitize_radiance(DN_LOAD3(emission, EMISSION_HALF, p)) : vec3(0.0); }

vec3 filtered(uint p) {
  vec3 c = DN_LOAD3(src, false, p);
  if (features.data[2u * p].w != DN_REFLECT_NONE || !dn_is_foreground(DN_LOAD1(depth, DEPTH_HALF, p))) return c;
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  vec3 colours[9];
  int count = 0;
  for (int yy = -1; yy <= 1; ++yy)
    for (int xx = -1; xx <= 1; ++xx) {
      ivec2 q = pos + ivec2(xx, yy);
      if (!dn_inside(q, frame.size.xy)) continue;
      uint qi = uint(q.y) * frame.size.x + uint(q.x);
      if (!dn_is_foreground(DN_LOAD1(depth, DEPTH_HALF, qi))) continue;
      if (features.data[2u * qi].w != DN_REFLECT_NONE) return c;
      colours[count] = DN_LOAD3(src, false, qi) - emitted(qi);
      ++count;
    }
  // Per channel, the value with as many smaller as larger ones (rank count / 2).
  int want = count / 2;
  vec3 median = c;
  for (int ch = 0; ch < 3; ++ch)
    for (int i = 0; i < count; ++i) {
      int below = 0, equal_before = 0;
      for (int j = 0; j < count; ++j) {
        below += colours[j][ch] < colours[i][ch] ? 1 : 0;
        equal_before += (colours[j][ch] == colours[i][ch] && j < i) ? 1 : 0;
      }
      if (below + equal_before == want) median[ch] = colours[i][ch];
    }
  return median + emitted(p);
}

void main() {
  uint pair = dn_invocation_index();
  uint p0 = 2u * pair;
  if (p0 >= frame.size.z) return;
  bool has_b = p0 + 1u < frame.size.z;
  vec3 a = filtered(p0);
  vec3 b = has_b ? filtered(p0 + 1u) : vec3(0.0);
  DN_STORE_RGB_PAIR(result, OUTPUT_HALF, pair, a, b, has_b)
}
