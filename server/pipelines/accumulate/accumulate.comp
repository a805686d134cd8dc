#version 450
// accumulate: temporal accumulation with reprojection (docs/pipelines.md).
// One invocation per pixel pair.
//
// Per foreground pixel p (finite depth > 0):
//   c      = sanitize(radiance)
//   p_prev = p + mv * frame.motion.xy
//   bilinear taps of p_prev, each accepted if inside the image, the previous
//   pixel was foreground, |z - z_prev| / max(z, z_prev) < depth_tolerance and
//   dot(n, n_prev) > normal_threshold; weights renormalised over accepted taps
//   prev, prev_len = weighted means of history colour and length over accepted
//   taps (prev_len = 0 when the accepted weight is < DN_MIN_TAP_WEIGHT, the
//   motion is not finite, or the reset flag is set)
//   len    = min(prev_len + 1, max_history)
//   alpha  = max(1 / len, alpha_min)
//   out    = mix(prev, c, alpha); history <- (out, len), (n, z)
// Background pixels: out = c, history <- (c, 0), (0, 0).
//
// Resources: accumulate.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "reproject.glsl"
#include "pass.glsl"
#include "generated/passes/accumulate.pass"

// Adds previous pixel q with bilinear weight w if it passes the tests.
void accumulate_tap(ivec2 q, float w, vec3 n, float z, inout vec3 sum_colour, inout float sum_len,
                    inout float sum_w) {
  uvec2 size = frame.size.xy;
  if (!dn_inside(q, size)) return;
  uint qi = uint(q.y) * size.x + uint(q.x);
  vec4 g = prev_geometry.data[qi];
  float z_prev = g.w;
  if (!(z_prev > 0.0)) return;  // previous pixel was background
  if (!(abs(z - z_prev) / max(z, z_prev) < DN_PARAM_VALUE(accumulate, depth_tolerance))) return;
  if (!(dot(n, g.xyz) > DN_PARAM_VALUE(accumulate, normal_threshold))) return;
  vec4 h = prev_colour.data[qi];
  sum_colour += w * h.rgb;
  sum_len += w * h.a;
  sum_w += w;
}

vec3 accumulate_pixel(uint p) {
  uvec2 size = frame.size.xy;
  vec3 c = dn_sanitize_radiance(DN_LOAD3(radiance, p));
  float z = DN_LOAD1(depth, p);
  if (!dn_is_foreground(z)) {
    cur_colour.data[p] = vec4(c, 0.0);
    cur_geometry.data[p] = vec4(0.0);
    return c;
  }
  vec3 n = dn_sanitize_normal(DN_LOAD3(normal, p));
  vec2 mv = DN_LOAD2(motion, p) * frame.motion.xy;

  vec3 prev = vec3(0.0);
  float prev_len = 0.0;
  ivec2 origin;
  vec4 weights;
  if ((frame.size.w & DN_FLAG_RESET) == 0u && dn_motion_usable(mv) &&
      dn_bilinear_footprint(dn_previous_position(p, size.x, mv), size, origin, weights)) {
    vec3 sum_colour = vec3(0.0);
    float sum_len = 0.0;
    float sum_w = 0.0;
    // The four taps, unrolled (no dynamic indexing of the weights).
    accumulate_tap(origin, weights.x, n, z, sum_colour, sum_len, sum_w);
    accumulate_tap(origin + ivec2(1, 0), weights.y, n, z, sum_colour, sum_len, sum_w);
    accumulate_tap(origin + ivec2(0, 1), weights.z, n, z, sum_colour, sum_len, sum_w);
    accumulate_tap(origin + ivec2(1, 1), weights.w, n, z, sum_colour, sum_len, sum_w);
    if (sum_w >= DN_MIN_TAP_WEIGHT) {
      prev = sum_colour / sum_w;
      prev_len = sum_len / sum_w;
    }
  }
  float len = min(prev_len + 1.0, DN_PARAM_VALUE(accumulate, max_history));
  float alpha = max(1.0 / len, DN_PARAM_VALUE(accumulate, alpha_min));
  vec3 result_colour = mix(prev, c, alpha);
  cur_colour.data[p] = vec4(result_colour, len);
  cur_geometry.data[p] = vec4(n, z);
  return result_colour;
}

void main() {
  uint pair = dn_invocation_index();
  uint n = frame.size.z;
  uint p0 = 2u * pair;
  if (p0 >= n) return;
  bool has_b = p0 + 1u < n;
  vec3 a = accumulate_pixel(p0);
  vec3 b = vec3(0.0);
  if (has_b) b = accumulate_pixel(p0 + 1u);
  DN_STORE_RGB_PAIR(result, pair, a, b, has_b)
}
