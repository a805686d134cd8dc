// Sample statistics of paper 003 (docs/pipelines.md, "stat"): a pixel's
// accumulator of Box-Cox samples y = 2 sqrt(x) - 2 per RGB channel, its
// skew-corrected mean and the variance of that mean, and the exact merge of
// two accumulators (IMPLEMENTATION-NOTES A.2 P0b; Chan et al., Pebay), which
// stat-temporal uses to carry statistics across frames.
#ifndef DN_STAT_GLSL
#define DN_STAT_GLSL

const float DN_FLT_EPSILON = 1.1920929e-7;

struct DnStat {
  float n;    // samples (fractional after scaling)
  vec3 mean;  // mean of y
  vec3 m2;    // sum of squared deviations of y
  vec3 m3;    // sum of cubed deviations of y
  vec3 raw;   // mean of the untransformed samples
};

DnStat dn_stat_empty() { return DnStat(0.0, vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0)); }

// The accumulator of one sample x (raw: what the raw mean holds for it).
DnStat dn_stat_sample(vec3 x, vec3 raw) { return DnStat(1.0, 2.0 * sqrt(max(x, 0.0)) - 2.0, vec3(0.0), vec3(0.0), raw); }

// Weighs an accumulator by f (fading, bilinear weights): n, M2 and M3 scale,
// so the means and the central moments M2 / n, M3 / n are kept.
DnStat dn_stat_scale(DnStat a, float f) { return DnStat(a.n * f, a.mean, a.m2 * f, a.m3 * f, a.raw); }

// The accumulator of the union of the samples of a and b.
DnStat dn_stat_merge(DnStat a, DnStat b) {
  float n = a.n + b.n;
  if (!(b.n > 0.0)) return a;
  if (!(a.n > 0.0)) return b;
  vec3 d = b.mean - a.mean;
  float fb = b.n / n;
  DnStat r;
  r.n = n;
  r.mean = a.mean + d * fb;
  r.m2 = a.m2 + b.m2 + d * d * (a.n * fb);
  r.m3 = a.m3 + b.m3 + d * d * d * (a.n * fb * (a.n - b.n) / n) + 3.0 * d * (a.n * b.m2 - b.n * a.m2) / n;
  r.raw = a.raw + (b.raw - a.raw) * fb;
  return r;
}

// Bessel-corrected sample variance of y (needs n > 1).
vec3 dn_stat_sample_variance(DnStat s) { return max(s.m2, 0.0) / (s.n - 1.0); }

// The skew-corrected mean theta = mean + (M3 / n) / (6 s2 n) where
// s2 > FLT_EPSILON, else the mean (paper 003 Alg. 2; Johnson 1978).
vec3 dn_stat_theta(DnStat s) {
  vec3 s2 = dn_stat_sample_variance(s);
  vec3 skew = (s.m3 / s.n) / (6.0 * s2 * s.n);
  return mix(s.mean, s.mean + skew, greaterThan(s2, vec3(DN_FLT_EPSILON)));
}

// The mean of the samples themselves from the Box-Cox moments (n > 0):
// x = (y / 2 + 1)^2 exactly, so mean(x) = (mean / 2 + 1)^2 + M2 / (4 n).
// Demodulated statistics (docs/protocol.md §7.7) carry no raw mean of their
// own on the wire; this is it, exact for any merge and fading.
vec3 dn_stat_raw_from_moments(DnStat s) {
  vec3 root = s.mean * 0.5 + 1.0;
  return root * root + max(s.m2, 0.0) / (4.0 * s.n);
}

// What turns a pixel's demodulated mean back into radiance: radiance /
// demodulated mean of the same samples (per channel; the samples' own
// albedos, exact for the pixel itself also where it straddles two
// surfaces), or the guarded albedo where either is 0 (no light to divide).
vec3 dn_stat_modulation(vec3 radiance, vec3 demodulated, vec3 albedo) {
  vec3 guarded = dn_guarded_albedo(albedo);
  return vec3(radiance.x > 0.0 && demodulated.x > 0.0 ? radiance.x / demodulated.x : guarded.x,
              radiance.y > 0.0 && demodulated.y > 0.0 ? radiance.y / demodulated.y : guarded.y,
              radiance.z > 0.0 && demodulated.z > 0.0 ? radiance.z / demodulated.z : guarded.z);
}

// A pixel's modulation given the frame's own statistics c (c.raw: its
// radiance): dn_stat_modulation where the frame brought samples, the
// guarded albedo where only history holds some, 1 where nothing is
// accumulated (the value is then the radiance itself).
vec3 dn_stat_pixel_modulation(DnStat c, bool accumulated, vec3 albedo) {
  if (!accumulated) return vec3(1.0);
  return c.n > 0.0 ? dn_stat_modulation(c.raw, dn_stat_raw_from_moments(c), albedo) : dn_guarded_albedo(albedo);
}

bool dn_stat_is_finite(DnStat s) {
  return dn_is_finite(s.n) && dn_is_finite(s.mean) && dn_is_finite(s.m2) && dn_is_finite(s.m3) && dn_is_finite(s.raw);
}

// Bounds of a frame's statistics (docs/pipelines.md "Guide sanitization"):
// at most 2^24 samples (exact in fp32; a larger count would outweigh every
// later frame of stat-temporal's history), and moments no sample within the
// radiance bound of the svgf family (1e12: y = 2 sqrt(x) - 2 <= DN_STAT_MAX_Y)
// can give: |mean| <= Y, M2 <= n Y^2, |M3| <= n Y^3. Without them one frame
// with M2 = 1e30 kept stat-temporal's output off a clean session's by 0.37
// of its brightest value, not decaying (guide_hard_cases_test.cpp).
const float DN_STAT_MAX_COUNT = 16777216.0;
const float DN_STAT_MAX_Y = 1999998.0;
bool dn_stat_usable(DnStat s) {
  const float y = DN_STAT_MAX_Y;
  return dn_stat_is_finite(s) && s.n > 0.0 && s.n <= DN_STAT_MAX_COUNT && all(lessThanEqual(abs(s.mean), vec3(y))) &&
         all(lessThanEqual(s.m2, vec3(s.n * y * y))) && all(lessThanEqual(abs(s.m3), vec3(s.n * y * y * y)));
}

#endif
