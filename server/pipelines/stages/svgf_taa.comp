#version 450
// svgf_taa: the final temporal anti-aliasing blend (taa_alpha or
// taa_static_alpha > 0; docs/pipelines.md, "svgf in detail", 5). Per pixel:
// where svgf_remodulate found a usable history (its blend weight a < 1), the
// reprojected previous final output is clamped per RGB channel to the
// min/max of the current colour over the 3x3 neighbourhood of p's surface
// (the taps inside the image at p's depth within 10 depth gradients, the
// reprojection's test, dn_same_depth: in HDR a light or its image beside p
// would open the box to its radiance and let a history smeared across the
// edge through; and no neighbour kept as rendered: svgf_remodulate marks
// those with a negative weight, -a, and what they show does not belong to
// the surface) and out = mix(clamped, current, a); elsewhere out = current.
// out goes to Output (session format; with TO_DISPLAY to the caller's vec4
// display frame) and to the TAA history, vec4(out, lag state) fp32.
// DISPLAY_LAG: the clamped value gives way to the unclamped one by
// max(previous.a, 0) (svgf_remodulate's display_lag), and previous.a is kept
// for the next frame. One invocation per pixel pair.
//
// Resources: svgf_taa.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "reproject.glsl"
#include "pass.glsl"
#include "generated/passes/svgf_taa.pass"

// The 3x3 depths around pos (0 outside the image: not foreground).
void depths_around(ivec2 pos, out float z[9]) {
  ivec2 size = ivec2(frame.size.xy);
  for (int k = 0; k < 9; ++k) {
    ivec2 q = pos + ivec2(k % 3 - 1, k / 3 - 1);
    bool inside = q.x >= 0 && q.y >= 0 && q.x < size.x && q.y < size.y;
    z[k] = inside ? DN_LOAD1(depth, uint(q.y) * frame.size.x + uint(q.x)) : 0.0;
  }
}

// The depth gradient of svgf.glsl's dn_svgf_gradients from the 3x3 depths:
// per axis the smaller one-sided difference over the foreground neighbours,
// then the larger of the two axes.
float depth_gradient(float z[9]) {
  float result = 0.0;
  for (int axis = 0; axis < 2; ++axis) {
    float a = z[axis == 0 ? 3 : 1], b = z[axis == 0 ? 5 : 7], best = 1e30;
    if (dn_is_foreground(a)) best = abs(a - z[4]);
    if (dn_is_foreground(b)) best = min(best, abs(b - z[4]));
    if (best < 1e30) result = max(result, best);
  }
  return result;
}

vec3 blend(uint p) {
  vec4 c = current_at(p);
  c.a = abs(c.a);
  vec3 out_c = c.rgb;
  if (c.a < 1.0) {
    ivec2 size = ivec2(frame.size.xy);
    ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
    float z[9];
    depths_around(pos, z);
    float grad = depth_gradient(z);
    vec3 lo = c.rgb, hi = c.rgb;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        ivec2 q = pos + ivec2(dx, dy);
        if (!dn_inside(q, uvec2(size))) continue;
        float zq = z[(dy + 1) * 3 + dx + 1];
        if (!dn_is_foreground(zq) || !dn_same_depth(z[4], grad, zq)) continue;  // another surface
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
    DN_STORE_RGB_PAIR(result, pair, a, b, has_b)
  }
}
