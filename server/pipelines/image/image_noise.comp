#version 450
// image_noise: the noise variance of a pixel's demodulated luminance, from
// the residuals r (image_prepare's .w) of the taps of its 5x5 neighbourhood
// on its surface (guide weight >= 1/2, p itself always), at most noise_cap
// times the frame's gain k (image_gain) times the guide-weighted mean
// luminance squared: a region noisier than the frame's median is
// underestimated there, so the cap errs towards filtering less.
//  - noise_estimate 0: the median of r^2 over 0.4549 (a chi-square median)
//    and 1.25 (E[r^2] for independent noise of equal variance): a firefly or
//    an edge among the taps, a minority, does not move it; the heavy-tailed
//    noise of few samples it underestimates.
//  - noise_estimate 1: r^2 less the mean of r's products with its right and
//    lower neighbours' residuals, averaged: for independent noise of variance
//    s2 that is 1.75 s2 (the covariance of neighbouring residuals is -0.5 s2),
//    while curvature of the signal smooth over a pixel cancels; shrunk by
//    the cube of its ratio to the plain mean of r^2 over 1.25, so where
//    structure still dominates (fine glossy detail) the filter trusts its
//    noise less. A mean: it follows heavy tails, and a small bright feature
//    beside p too.
// One invocation per pixel.
//
// Resources: image_noise.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "pass.glsl"
#include "generated/passes/image_noise.pass"
#include "image.glsl"
#include "image_gain.glsl"
#include "luminance.glsl"

void main() {
  const ivec2 size = ivec2(frame.size.xy);
  const uint pi = dn_invocation_index();
  if (pi >= frame.size.z) return;
  const ivec2 p = ivec2(int(pi % uint(size.x)), int(pi / uint(size.x)));

  const vec4 sp = signal_at(pi);
  const vec4 gp = guide_at(pi);
  const vec3 ap = dn_image_albedo(pi);
  const bool decorrelated_estimate = DN_PARAM_VALUE(image, noise_estimate) != 0.0;
  float r2[25];  // the squared residuals of the taps on p's surface, sorted (median estimate)
  int n = 0;
  float mean = 0.0, weight = 0.0, plain = 0.0, decorrelated = 0.0;
  for (int y = -2; y <= 2; ++y)
    for (int x = -2; x <= 2; ++x) {
      const ivec2 q = p + ivec2(x, y);
      if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
      const uint qi = uint(q.y) * uint(size.x) + uint(q.x);
      const float w = x == 0 && y == 0 ? 1.0
                                       : dn_image_geometry_weight(gp, guide_at(qi), ap, dn_image_albedo(qi),
                                                                  length(vec2(x, y)));
      const vec4 sq = signal_at(qi);
      mean += w * dn_luminance(sq.rgb);
      weight += w;
      if (w < 0.5) continue;
      const float r = sq.w;
      if (decorrelated_estimate) {
        const float r_right = signal_at(dn_image_clamped(q, ivec2(1, 0), size)).w;
        const float r_lower = signal_at(dn_image_clamped(q, ivec2(0, 1), size)).w;
        plain += r * r;
        decorrelated += r * r - 0.5 * r * (r_right + r_lower);
        ++n;
        continue;
      }
      int k = n++;
      for (; k > 0 && r2[k - 1] > r * r; --k) r2[k] = r2[k - 1];
      r2[k] = r * r;
    }
  float local;
  if (decorrelated_estimate) {
    const float from_plain = plain / (1.25 * float(n));
    const float from_decorrelated = max(decorrelated, 0.0) / (1.75 * float(n));
    const float noise_share = from_plain > 0.0 ? min(1.0, from_decorrelated / from_plain) : 0.0;
    local = from_decorrelated * noise_share * noise_share * noise_share;
  } else {
    local = r2[n / 2] * DN_GAIN_MEDIAN_TO_MEAN / 1.25;
  }
  const float gain = uintBitsToFloat(histogram.data[GAIN_BINS]);
  const float m = mean / weight;
  const float cap = DN_PARAM_VALUE(image, noise_cap);
  noisy.data[pi] = vec4(sp.rgb, cap > 0.0 ? min(local, cap * gain * m * m) : local);
}
