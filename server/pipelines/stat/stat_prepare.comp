#version 450
// stat_prepare: the per-pixel inputs of the Welch test (paper 003 Alg. 2;
// docs/pipelines.md, "stat"), per RGB channel of the sample statistics:
//   s2    = M2 / (n - 1)                       Bessel-corrected sample variance
//   var   = max(M2 / (n (n - 1)), variance_floor)   variance of the mean
//   theta = mean + (M3 / n) / (6 s2 n)   if s2 > FLT_EPSILON, else mean
//           (skew correction of the Box-Cox mean, Johnson 1978)
// A pixel with 0 < n < 2 (one sample has no variance) gets theta = its
// Box-Cox mean and variance 0 (stat_filter tests it against its neighbours'
// variances), or with pool_single (stat-temporal's default) a sample
// variance from its 3x3 window's usable statistics (quadrant_variance) over
// its own n, and the whole window's sample count in theta.w (as SVGF
// estimates a young pixel's variance from its neighbourhood): from the
// radiance alone every pixel of a first frame has one sample, and none would
// have a variance to test. Its theta stays its own mean: the window's mean
// made a light seen in a mirror one with its dark neighbours (dnrender scene
// 6, first frame: RMSE 0.593 against the frame's 0.517). n = 0 or any
// non-finite statistic gets n = 0 in theta.w: no data. variance.w is p's
// class (stat_class.glsl), with CLASSIFY (stat-temporal): DN_STAT_MOVING
// where the pixel moves (motion not usable or 0.005 px or more):
// stat_filter tests its neighbours by Eq. 14 there; DN_STAT_KEPT where an
// unexplained pixel (dn_unexplained: a metal or mirror, whose guides say
// nothing of what it shows) moves, or is still with 2 or more samples:
// stat_filter returns its own mean (moving: its frame, stat_temporal keeps
// no history there). Its few samples' variance is so wide that the test
// accepted dark neighbours into a highlight (dnrender scene 6 after 2 still
// frames: a lit line of reference 25 shown at 0.55, its mean 15), at 64
// samples it still let darker neighbours of high variance in, and a moving
// one's variance, pooled from its window, counts a sharp reflection's edges
// as noise; svgf's chain keeps such pixels too. Else DN_STAT_POOLED where
// pool_single gave the variance, DN_STAT_TESTED elsewhere. One invocation
// per pixel.
//
// DEMODULATED (the statistics are over demodulated samples): also the
// value stat_filter averages, the demodulated mean from the moments
// (dn_stat_raw_from_moments; no data: the sanitized radiance, returned as
// it is), and with MODULATION (stat: the sources are the frame's planes)
// what remodulates p's result, dn_stat_modulation (no data: 1).
//
// Resources: stat_prepare.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "inside.glsl"
#include "reproject.glsl"
#include "stat.glsl"
#include "stat_class.glsl"
#include "pass.glsl"
#include "generated/passes/stat_prepare.pass"

void store3(uint p, vec3 v, bool to_modulation) {
  for (uint c = 0u; c < 3u; ++c) {
    if (to_modulation) modulation.data[3u * p + c] = v[c];
    else value.data[3u * p + c] = v[c];
  }
}

// The demodulated value and modulation of pixel p with statistics s (n = 0: none).
void demodulate(uint p, DnStat s) {
  bool has_data = s.n > 0.0;
  s.raw = dn_sanitize_radiance(DN_LOAD3(radiance, p));
  store3(p, has_data ? dn_stat_raw_from_moments(s) : s.raw, false);
  if (MODULATION) store3(p, dn_stat_pixel_modulation(s, has_data, DN_LOAD3(albedo, p)), true);
}

DnStat stat_at(uint p) {
  DnStat s;
  s.n = count.data[p];
  s.mean = vec3(mean.data[3u * p], mean.data[3u * p + 1u], mean.data[3u * p + 2u]);
  s.m2 = vec3(m2.data[3u * p], m2.data[3u * p + 1u], m2.data[3u * p + 2u]);
  s.m3 = vec3(m3.data[3u * p], m3.data[3u * p + 1u], m3.data[3u * p + 2u]);
  s.raw = vec3(0.0);  // not read here: stat_filter reads the raw means
  return s;
}

// The sample count of the usable statistics of p's 3x3 window, summed in row order.
float window_count(uint p) {
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  float n = 0.0;
  [[dont_unroll]] for (int o = 0; o < 9; ++o) {
    ivec2 q = pos + ivec2(o % 3 - 1, o / 3 - 1);
    if (!dn_inside(q, frame.size.xy)) continue;
    DnStat t = stat_at(uint(q.y) * frame.size.x + uint(q.x));
    if (dn_stat_usable(t)) n += t.n;
  }
  return n;
}

// A one-sample pixel's sample variance: per channel the second smallest of
// the sample variances of the merges of the four 2x2 quadrants of p's 3x3
// window that hold p (each merged in row order), of those with 2 or more
// samples; the smallest where only one has; none (count 0) where none has.
// The whole window's variance counts a neighbouring highlight, firefly or
// edge as noise, and p then accepted it in stat_filter; a bright pixel next
// to p lies in at most two of the quadrants, so the second smallest is clear
// of it, and of the downward bias of the smallest.
vec3 quadrant_variance(uint p, out float count) {
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  vec3 smallest = vec3(0.0), second = vec3(0.0);
  count = 0.0;
  [[dont_unroll]] for (int quadrant = 0; quadrant < 4; ++quadrant) {
    ivec2 corner = pos - ivec2(1 - quadrant % 2, 1 - quadrant / 2);
    DnStat acc = dn_stat_empty();
    for (int k = 0; k < 4; ++k) {
      ivec2 q = corner + ivec2(k % 2, k / 2);
      if (!dn_inside(q, frame.size.xy)) continue;
      DnStat t = stat_at(uint(q.y) * frame.size.x + uint(q.x));
      if (dn_stat_usable(t)) acc = dn_stat_merge(acc, t);
    }
    if (!(acc.n >= 2.0)) continue;
    vec3 v = dn_stat_sample_variance(acc);
    second = count == 0.0 ? v : count == 1.0 ? max(smallest, v) : min(second, max(smallest, v));
    smallest = count == 0.0 ? v : min(smallest, v);
    count += 1.0;
  }
  return count >= 2.0 ? second : smallest;
}

float pixel_class = DN_STAT_TESTED;  // variance.w

bool pixel_moves(uint p) {
  vec2 mv = DN_LOAD2(motion, p) * frame.motion.xy;
  return !dn_motion_usable(mv) || !dn_is_still(mv);
}

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  bool moves = CLASSIFY && pixel_moves(p);
  bool unexplained = CLASSIFY && dn_unexplained(DN_LOAD3(albedo, p));
  if (moves) pixel_class = unexplained ? DN_STAT_KEPT : DN_STAT_MOVING;
  DnStat s = stat_at(p);
  if (!dn_stat_usable(s)) {
    theta.data[p] = vec4(0.0);
    variance.data[p] = vec4(0.0);
    if (DEMODULATED) demodulate(p, dn_stat_empty());
    return;
  }
  if (DEMODULATED) demodulate(p, s);
  if (DN_PARAM_VALUE(stat, pool_single) != 0.0 && s.n < 2.0) {
    float quadrants;
    vec3 s2 = quadrant_variance(p, quadrants);
    if (quadrants > 0.0) {  // then the window holds 2 or more samples too
      vec3 var = max(s2 / s.n, vec3(DN_PARAM_VALUE(stat, variance_floor)));
      theta.data[p] = vec4(s.mean, window_count(p));
      variance.data[p] = vec4(var, pixel_class == DN_STAT_TESTED ? DN_STAT_POOLED : pixel_class);
      return;
    }
  }
  if (s.n < 2.0) {  // samples but no variance: the mean, for the single-sample test
    theta.data[p] = vec4(s.mean, s.n);
    variance.data[p] = vec4(vec3(0.0), pixel_class);
    return;
  }
  if (unexplained) pixel_class = DN_STAT_KEPT;
  vec3 var = max(dn_stat_sample_variance(s) / s.n, vec3(DN_PARAM_VALUE(stat, variance_floor)));
  theta.data[p] = vec4(dn_stat_theta(s), s.n);
  variance.data[p] = vec4(var, pixel_class);
}
