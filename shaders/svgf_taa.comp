#version 450
// svgf_taa: the final temporal anti-aliasing blend (taa_alpha or
// taa_static_alpha > 0; docs/pipelines.md, "svgf in detail", 5). Per pixel:
// where svgf_remodulate found a usable history (its blend weight a < 1), the
// reprojected previous final output is clamped per RGB channel to the
// min/max of the current colour over the 3x3 neighbourhood (the taps inside
// the image, but no neighbour kept as rendered: svgf_remodulate marks those
// with a negative weight, -a, and what they show does not belong to the
// surface) and out = mix(clamped, current, a); elsewhere out = current.
// out goes to Output (session format; with TO_DISPLAY to the caller's vec4
// display frame) and to the TAA history, vec4(out, lag state) fp32.
// DISPLAY_LAG: the clamped value gives way to the unclamped one by
// max(previous.a, 0) (svgf_remodulate's display_lag), and previous.a is kept
// for the next frame. One invocation per pixel pair.
//
// Resources: passes/svgf_taa.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "pass.glsl"
#include "passes/svgf_taa.pass"

vec3 blend(uint p) {
  vec4 c = current_at(p);
  c.a = abs(c.a);
  vec3 out_c = c.rgb;
  if (c.a < 1.0) {
    ivec2 size = ivec2(frame.size.xy);
    ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
    vec3 lo = c.rgb, hi = c.rgb;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        ivec2 q = pos + ivec2(dx, dy);
        if (q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) continue;
        vec4 cq = current_at(uint(q.y) * frame.size.x + uint(q.x));
        if (cq.a < 0.0) continue;  // kept as rendered (p itself is already in)
        vec3 v = cq.rgb;
        lo = min(lo, v);
        hi = max(hi, v);
      }
    vec4 reprojected = previous_at(p);
    vec3 prev = clamp(reprojected.rgb, lo, hi);
    if (DISPLAY_LAG) prev = mix(prev, reprojected.rgb, max(reprojected.a, 0.0));
    out_c = mix(prev, c.rgb, c.a);
  }
  history.data[p] = vec4(out_c, DISPLAY_LAG ? previous_at(p).a : 0.0);
  return out_c;
}

void main() {
  uint pair = dn_invocation_index();
  uint n = frame.size.z;
  uint p0 = 2u * pair;
  if (p0 >= n) return;
  bool has_b = p0 + 1u < n;
  vec3 a = blend(p0);
  vec3 b = vec3(0.0);
  if (has_b) b = blend(p0 + 1u);
  if (TO_DISPLAY) {
    display.data[p0] = vec4(a, 0.0);
    if (has_b) display.data[p0 + 1u] = vec4(b, 0.0);
  } else {
    DN_STORE_RGB_PAIR(result, OUTPUT_HALF, pair, a, b, has_b)
  }
}
