#version 450
// stat_temporal: temporal sample statistics for stat-temporal (paper 003 §8's
// future work; docs/pipelines.md, "stat-temporal"). Per pixel p:
//   C  = the frame's statistics (count, Box-Cox mean, M2, M3, raw mean =
//        the sanitized radiance); non-finite statistics or n <= 0: no data;
//        without statistics planes (FROM_RADIANCE) the radiance is one
//        sample: n = 1, mean y(x), M2 = M3 = 0
//   H  = the previous accumulators under p's bilinear footprint at
//        p_prev = p + mv, the taps on the same surface (Falcor's SVGF test),
//        each weighed by its renormalised bilinear weight and merged
//   beta = mix(fading, 1, stillness(mv)): H's n, M2 and M3 scaled by beta
//        (a still pixel keeps all its samples, a moving one a fading memory);
//        at an unexplained pixel (dn_unexplained: a mirror or metal) fading
//        is 0, a moving one keeps none: what it shows does not move with its
//        surface, and the Welch test cannot reject a history that holds a
//        reflected highlight's samples (their variance is too large), so a
//        fading memory trailed the highlight (stat_prepare keeps the pixel's
//        own frame)
//   test: the Welch test of stat_filter, between the history and the
//        frame over p's 3x3 window (the same-surface previous pixels around
//        p_prev, merged and faded, against the same-surface current pixels
//        around p, merged), per channel with the Welch-Satterthwaite nu, at
//        history_alpha; one sample's test would reject on every firefly, the
//        window's rejects what changed. The frame's sample variance is shrunk
//        toward the history's by DN_PRIOR_DOF pseudo-samples: under the
//        hypothesis tested they share a distribution, and nine samples of
//        sparse light are often all 0 (a variance of 0).
//   accumulator = C (the history is rejected: a moved shadow or highlight, a
//        ghost) when the test fails by more than 2t standard errors at a
//        moving pixel, or fails for the second frame in a row (p's previous
//        pixel is marked suspect): a failure at alpha that chance explains
//        (about 3 alpha of the frames of a still pixel) costs no history, and
//        at a still pixel neither does one firefly in the window (rejected at
//        once, the pixel kept the firefly as its only sample). Else
//        merge(H, C), the exact parallel merge, marking p suspect when the
//        test failed.
//        Windows with fewer than 2 samples pass.
// Background pixels, the first frame and a reset keep C alone. With
// demodulated statistics also p's modulation (store_modulation). One
// invocation per pixel.
//
// Resources: stat_temporal.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "reproject.glsl"
#include "stat.glsl"
#include "pass.glsl"
#include "generated/passes/stat_temporal.pass"

#include "svgf.glsl"

#define DN_READ3(plane, p) vec3(plane.data[3u * (p)], plane.data[3u * (p) + 1u], plane.data[3u * (p) + 2u])

// The frame's statistics at pixel q (no data: n = 0). FROM_RADIANCE: its
// sanitized radiance is one sample (demodulated: over q's guarded albedo).
DnStat current_stat(uint q) {
  vec3 x = dn_sanitize_radiance(DN_LOAD3(radiance, q));
  if (FROM_RADIANCE) return dn_stat_sample(DEMODULATED ? x / dn_guarded_albedo(DN_LOAD3(albedo, q)) : x, x);
  DnStat s = DnStat(count.data[q], DN_READ3(mean, q), DN_READ3(m2, q), DN_READ3(m3, q), x);
  return dn_stat_usable(s) ? s : dn_stat_empty();
}

DnStat previous_stat(uint q) {
  return DnStat(prev_count.data[q], DN_READ3(prev_mean, q), DN_READ3(prev_m2, q), DN_READ3(prev_m3, q),
                DN_READ3(prev_raw, q));
}

// Whether previous pixel q left history on the surface of the current pixel
// (depth z, normal n, gradients grad).
bool previous_on_surface(ivec2 q, float z, vec3 n, vec2 grad) {
  if (!dn_inside(q, frame.size.xy)) return false;
  uvec4 g = prev_geometry.data[uint(q.y) * frame.size.x + uint(q.x)];
  float z_prev = uintBitsToFloat(g.x);
  return z_prev > 0.0 && dn_same_surface(z, n, grad, z_prev, dn_svgf_unpack_normal(g.y));
}

void add_tap(ivec2 q, float w, float z, vec3 n, vec2 grad, inout DnStat taps[4], inout float weights[4], int k) {
  if (w > 0.0 && previous_on_surface(q, z, n, grad)) {
    taps[k] = previous_stat(uint(q.y) * frame.size.x + uint(q.x));
    weights[k] = w;
  }
}

// p's history: the same-surface taps of its bilinear footprint, merged with
// their renormalised weights (n = 0: none).
DnStat reprojected(ivec2 origin, vec4 w, float z, vec3 n, vec2 grad) {
  DnStat taps[4] = DnStat[4](dn_stat_empty(), dn_stat_empty(), dn_stat_empty(), dn_stat_empty());
  float weights[4] = float[4](0.0, 0.0, 0.0, 0.0);
  add_tap(origin, w.x, z, n, grad, taps, weights, 0);
  add_tap(origin + ivec2(1, 0), w.y, z, n, grad, taps, weights, 1);
  add_tap(origin + ivec2(0, 1), w.z, z, n, grad, taps, weights, 2);
  add_tap(origin + ivec2(1, 1), w.w, z, n, grad, taps, weights, 3);
  float sum = weights[0] + weights[1] + weights[2] + weights[3];
  DnStat h = dn_stat_empty();
  if (sum < DN_MIN_TAP_WEIGHT) return h;
  for (int k = 0; k < 4; ++k)
    if (weights[k] > 0.0) h = dn_stat_merge(h, dn_stat_scale(taps[k], weights[k] / sum));
  return h;
}

// The Welch-Satterthwaite degrees of freedom of the difference of two means
// with variances var_a, var_b from na, nb samples (the history's n dwarfs
// the frame's, so the pooled nu = na + nb - 2 would overstate the frame's
// certainty), as a table index + 1; both variances 0: the pooled nu.
uint welch_nu(float var_a, float na, float var_b, float nb) {
  float den = var_a * var_a / (na - 1.0) + var_b * var_b / (nb - 1.0);
  float nu = den > 0.0 ? (var_a + var_b) * (var_a + var_b) / den : na + nb - 2.0;
  return uint(clamp(nu, 1.0, float(TABLE_SIZE)));
}

// The Welch test between the history and the frame over p's 3x3 window:
// DN_HISTORY_PASSES, or how it fails: DN_HISTORY_FAILS (the difference of
// the means exceeds t standard errors in some channel) or DN_HISTORY_FAILS_FAR
// (2t: no chance failure of a test at alpha).
const uint DN_HISTORY_PASSES = 0u, DN_HISTORY_FAILS = 1u, DN_HISTORY_FAILS_FAR = 2u;
const float DN_PRIOR_DOF = 2.0;
uint history_test(ivec2 pos, ivec2 prev, float z, vec3 n, vec2 grad, float beta) {
  DnStat h = dn_stat_empty(), c = dn_stat_empty();
  for (int yy = -1; yy <= 1; ++yy)
    for (int xx = -1; xx <= 1; ++xx) {
      ivec2 q = prev + ivec2(xx, yy);
      if (previous_on_surface(q, z, n, grad)) h = dn_stat_merge(h, previous_stat(uint(q.y) * frame.size.x + uint(q.x)));
      q = pos + ivec2(xx, yy);
      if (!dn_inside(q, frame.size.xy)) continue;
      uint qi = uint(q.y) * frame.size.x + uint(q.x);
      float zq = dn_svgf_depth(qi);
      if (dn_is_foreground(zq) && dn_same_surface(z, n, grad, zq, dn_svgf_normal(qi)))
        c = dn_stat_merge(c, current_stat(qi));
    }
  h = dn_stat_scale(h, beta);
  if (h.n < 2.0 || c.n < 2.0) return DN_HISTORY_PASSES;
  vec3 d = dn_stat_theta(h) - dn_stat_theta(c);
  vec3 s2h = dn_stat_sample_variance(h);
  vec3 s2c = ((c.n - 1.0) * dn_stat_sample_variance(c) + DN_PRIOR_DOF * s2h) / (c.n - 1.0 + DN_PRIOR_DOF);
  vec3 var_h = s2h / h.n, var_c = s2c / c.n;
  vec3 t2 = vec3(t_squared.data[welch_nu(var_h.x, h.n, var_c.x, c.n) - 1u],
                 t_squared.data[welch_nu(var_h.y, h.n, var_c.y, c.n) - 1u],
                 t_squared.data[welch_nu(var_h.z, h.n, var_c.z, c.n) - 1u]);
  vec3 bound = t2 * (var_h + var_c);
  if (all(lessThanEqual(d * d, bound))) return DN_HISTORY_PASSES;
  return any(greaterThan(d * d, 4.0 * bound)) ? DN_HISTORY_FAILS_FAR : DN_HISTORY_FAILS;
}

void store(uint p, DnStat s, float z, vec3 n, bool suspect) {
  acc_count.data[p] = s.n;
  for (uint c = 0u; c < 3u; ++c) {
    acc_mean.data[3u * p + c] = s.mean[c];
    acc_m2.data[3u * p + c] = s.m2[c];
    acc_m3.data[3u * p + c] = s.m3[c];
    acc_raw.data[3u * p + c] = s.raw[c];
  }
  acc_geometry.data[p] = z > 0.0 ? uvec4(floatBitsToUint(z), dn_svgf_pack_normal(n), suspect ? 1u : 0u, 0u) : uvec4(0u);
}

// DEMODULATED: what stat_filter multiplies p's result by, from this
// frame's own samples (dn_stat_pixel_modulation): the accumulators cannot
// give it.
void store_modulation(uint p, DnStat c, DnStat acc) {
  if (!DEMODULATED) return;
  vec3 m = dn_stat_pixel_modulation(c, acc.n > 0.0, DN_LOAD3(albedo, p));
  for (uint k = 0u; k < 3u; ++k) modulation.data[3u * p + k] = m[k];
}

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  uvec2 size = frame.size.xy;
  ivec2 pos = ivec2(p % size.x, p / size.x);
  DnStat c = current_stat(p);
  float z = dn_svgf_depth(p);
  vec3 n = dn_svgf_normal(p);
  if (!dn_is_foreground(z) || !(dot(n, n) > 0.0)) {
    store(p, c, 0.0, vec3(0.0), false);
    store_modulation(p, c, c);
    return;
  }
  vec2 grad = dn_svgf_gradients(pos, z, n);
  vec2 mv = DN_LOAD2(motion, p) * frame.motion.xy;
  ivec2 origin;
  vec4 w;
  DnStat acc = c;
  bool suspect = false;
  if ((frame.size.w & DN_FLAG_RESET) == 0u && dn_motion_usable(mv) &&
      dn_bilinear_footprint(dn_previous_position(p, size.x, mv), size, origin, w)) {
    float fading = dn_unexplained(DN_LOAD3(albedo, p)) ? 0.0 : DN_PARAM_VALUE(stat_temporal, fading);
    float beta = mix(fading, 1.0, dn_stillness(mv));
    DnStat h = dn_stat_scale(reprojected(origin, w, z, n, grad), beta);
    ivec2 prev = ivec2(floor(dn_previous_position(p, size.x, mv)));
    if (h.n > 0.0) {
      uint test = history_test(pos, prev, z, n, grad, beta);
      bool was_suspect = dn_inside(prev, size) && prev_geometry.data[uint(prev.y) * size.x + uint(prev.x)].z != 0u;
      bool far = test == DN_HISTORY_FAILS_FAR && !dn_is_still(mv);
      if (far || (test != DN_HISTORY_PASSES && was_suspect)) {
        acc = c;  // rejected
      } else {
        acc = dn_stat_merge(h, c);
        suspect = test != DN_HISTORY_PASSES;
      }
    }
  }
  store(p, acc, z, n, suspect);
  store_modulation(p, c, acc);
}
