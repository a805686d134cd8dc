#version 450
// stat_filter: the statistical denoiser's gather (paper 003 Alg. 2, Eq. 4,
// 10, 12-16; docs/pipelines.md, "stat"). For pixel p with statistics, over
// the disc |q - p| <= radius (taps inside the image):
//   member(p, q): every RGB channel passes the Welch test
//       symmetric:  (theta_p - theta_q)^2 <= t^2 (var_p + var_q)
//       asymmetric: (theta_p - theta_q)^2 <  var_p (1 + 2 t^2) - var_q
//                   (Eq. 14 by its inequality, never through a NaN; equal
//                   means with zero variances are members)
//     t = the two-sided quantile for nu = n_p + n_q - 2 (per pair, so unequal
//     sample counts are exact), read as t^2 from the host's table
//   weight(p, q) = exp(-|q - p|^2 / (2 s_s^2) - |a_p - a_q|^2 / (2 s_a^2)
//                      - |n_p - n_q|^2 / (2 s_n^2))   (Eq. 16, the authors'
//                      code's standard deviations)
//   out_p = (raw_p + sum over members q != p of weight * raw_q) / (1 + sum of weights),
//           computed as raw_p + sum weight * (raw_q - raw_p) / (1 + sum of weights)
//           so that a constant image comes back exactly
// raw is the sanitized radiance (the raw mean). membership 0: every tap with
// statistics is a member (the base filter alone). A pixel without statistics
// (theta.w = 0) is nobody's member and keeps its raw mean. One invocation per
// pixel pair.
//
// Resources: passes/stat_filter.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "pass.glsl"
#include "passes/stat_filter.pass"

bool member(vec3 d2, float t2, vec3 var_p, vec3 var_q) {
  if (DN_PARAM_VALUE(stat, asymmetric) != 0.0) {
    bvec3 pass_ = lessThan(d2, var_p * (1.0 + 2.0 * t2) - var_q);
    bvec3 tie = equal(d2 + var_p + var_q, vec3(0.0));  // equal means, no variance: w* = 0/0, accepted
    return all(bvec3(pass_.x || tie.x, pass_.y || tie.y, pass_.z || tie.z));
  }
  return all(lessThanEqual(d2, t2 * (var_p + var_q)));
}

vec3 filter_pixel(uint p) {
  vec3 raw_p = dn_sanitize_radiance(DN_LOAD3(radiance, RADIANCE_HALF, p));
  vec4 theta_p = theta.data[p];
  if (theta_p.w < 2.0) return raw_p;
  ivec2 size = ivec2(frame.size.xy);
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  vec3 var_p = variance.data[p].rgb;
  vec3 albedo_p = DN_LOAD3(albedo, ALBEDO_HALF, p);
  vec3 normal_p = dn_sanitize_normal(DN_LOAD3(normal, NORMAL_HALF, p));
  int r = int(DN_PARAM_VALUE(stat, radius));
  float ks = -0.5 / (DN_PARAM_VALUE(stat, sigma_spatial) * DN_PARAM_VALUE(stat, sigma_spatial));
  float ka = -0.5 / (DN_PARAM_VALUE(stat, sigma_albedo) * DN_PARAM_VALUE(stat, sigma_albedo));
  float kn = -0.5 / (DN_PARAM_VALUE(stat, sigma_normal) * DN_PARAM_VALUE(stat, sigma_normal));
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
      vec4 theta_q = theta.data[q];
      if (theta_q.w < 2.0) continue;
      vec3 d = theta_p.rgb - theta_q.rgb;
      uint nu = uint(theta_p.w + theta_q.w + 0.5) - 2u;  // >= 2
      float t2 = t_squared.data[min(nu, TABLE_SIZE) - 1u];
      if (DN_PARAM_VALUE(stat, membership) != 0.0 && !member(d * d, t2, var_p, variance.data[q].rgb)) continue;
      vec3 da = albedo_p - DN_LOAD3(albedo, ALBEDO_HALF, q);
      vec3 dn = normal_p - dn_sanitize_normal(DN_LOAD3(normal, NORMAL_HALF, q));
      float w = exp(ks * float(d2xy) + ka * dot(da, da) + kn * dot(dn, dn));
      sum += w * (dn_sanitize_radiance(DN_LOAD3(radiance, RADIANCE_HALF, q)) - raw_p);
      weight_sum += w;
    }
  }
  return raw_p + sum / weight_sum;
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
  DN_STORE_RGB_PAIR(result, OUTPUT_HALF, pair, a, b, has_b)
}
