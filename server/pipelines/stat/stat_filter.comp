#version 450
// stat_filter: the statistical denoiser's gather (paper 003 Alg. 2, Eq. 4,
// 10, 12-16; docs/pipelines.md, "stat"). For pixel p with statistics, over
// the disc |q - p| <= radius (taps inside the image):
//   member(p, q): every RGB channel passes the Welch test
//       symmetric:  (theta_p - theta_q)^2 <= t^2 (var_p + var_q)
//       asymmetric: (theta_p - theta_q)^2 <  var_p (1 + 2 t^2) - var_q
//                   (Eq. 14 by its inequality, never through a NaN; equal
//                   means with zero variances are members), with parameter
//                   asymmetric or where stat_prepare marked p moving
//                   (stat-temporal)
//     t = the two-sided quantile for nu = n_p + n_q - 2 (per pair, so unequal
//     sample counts are exact), read as t^2 from the host's table at alpha,
//     or at still_alpha where p and q are both DN_STAT_TESTED (still, with
//     statistics of their own: stat-temporal's accumulated means)
//   weight(p, q) = exp(-|q - p|^2 / (2 s_s^2) - |a_p - a_q|^2 / (2 s_a^2)
//                      - |n_p - n_q|^2 / (2 s_n^2))   (Eq. 16, the authors'
//                      code's standard deviations; with spatial_shrink_from
//                      N a still p of n > N samples has s_s sqrt(N / n) and
//                      its disc 3 of those at most)
//   out_p = (raw_p + sum over members q != p of weight * raw_q) / (1 + sum of weights),
//           computed as raw_p + sum weight * (raw_q - raw_p) / (1 + sum of weights)
//           so that a constant image comes back exactly
// raw is the sanitized radiance (the raw mean); with demodulated statistics
// (DEMODULATED) stat_prepare's demodulated mean, and out_p is multiplied by
// p's modulation. membership 0: every tap with
// statistics is a member (the base filter alone). Only pixels with
// statistics (n >= 2) are members. A pixel with a sample but no variance
// (0 < n_p < 2: one sample, or a reset history at 1 spp) gathers with the
// single-sample form of the test, its variance taken from the neighbour's
// sample variance, var_p = var_q n_q / n_p, and nu = n_q - 1 (a prediction
// interval: is p's sample plausible under q's distribution). A pixel without
// data (n = 0, or a non-finite statistic) keeps its raw mean, and so does a
// pixel stat_prepare marked kept (DN_STAT_KEPT). One invocation per pixel pair.
//
// Resources: stat_filter.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "pass.glsl"
#include "generated/passes/stat_filter.pass"

#include "stat_filter_io.glsl"
#include "stat_class.glsl"
#include "stat_gather.glsl"

vec3 filter_pixel(uint p) {
  vec3 raw_p = dn_stat_value(p);
  vec4 theta_p = theta_at(p);
  vec4 var_p4 = variance_at(p);
  if (!(theta_p.w > 0.0) || var_p4.w == DN_STAT_KEPT) return dn_stat_remodulate(raw_p, p);
  ivec2 size = ivec2(frame.size.xy);
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  vec3 var_p = var_p4.rgb;
  vec3 albedo_p = dn_sanitize_albedo(DN_LOAD3(albedo, p));
  vec3 normal_p = dn_sanitize_normal(DN_LOAD3(normal, p));
  int r = int(DN_PARAM_VALUE(stat, radius));
  DnStatKernel k = dn_stat_kernel_from_parameters();
  k.asymmetric = k.asymmetric || var_p4.w == DN_STAT_MOVING;
  dn_stat_narrow_still(k, r, theta_p, var_p4.w);
  vec3 sum = vec3(0.0);  // of weight * (raw_q - raw_p)
  float weight_sum = 1.0;
  for (int dy = -r; dy <= r; ++dy) {
    int y = pos.y + dy;
    if (y < 0 || y >= size.y) continue;
    for (int dx = -r; dx <= r; ++dx) {
      int x = pos.x + dx;
      int d2xy = dx * dx + dy * dy;
      if (x < 0 || x >= size.x || d2xy > r * r || d2xy == 0) continue;
      uint q = uint(y) * frame.size.x + uint(x);
      vec4 var_q4 = variance_at(q);
      bool still = var_p4.w == DN_STAT_TESTED && var_q4.w == DN_STAT_TESTED;
      float m = dn_stat_membership(theta_p, var_p, theta_at(q), var_q4.rgb, k, still);
      if (m == 0.0) continue;
      vec3 da = albedo_p - dn_sanitize_albedo(DN_LOAD3(albedo, q));
      vec3 dn = normal_p - dn_sanitize_normal(DN_LOAD3(normal, q));
      float w = m * dn_stat_base_weight(d2xy, da, dn, k);
      sum += w * (dn_stat_value(q) - raw_p);
      weight_sum += w;
    }
  }
  return dn_stat_remodulate(raw_p + sum / weight_sum, p);
}

void main() {
  uint pair = dn_invocation_index();
  uint n = frame.size.z;
  uint p0 = 2u * pair;
  if (p0 >= n) return;
  bool has_b = p0 + 1u < n;
  vec3 a = filter_pixel(p0);
  vec3 b = vec3(0.0);
  if (has_b) b = filter_pixel(p0 + 1u);
  DN_STORE_RGB_PAIR(result, pair, a, b, has_b)
}
