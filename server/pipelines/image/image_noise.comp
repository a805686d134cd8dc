#version 450
// image_noise: the noise variance of a pixel's demodulated luminance over
// its 5x5 neighbourhood: the median of the squared residuals (image_prepare's
// .w) of the taps its guides put on p's surface (weight >= 1/2), over
// 0.4549 (a chi-square median) and 1.25 (a residual's variance for
// independent noise of equal variance), which structure covering most of
// the window inflates, at most noise_cap times the frame's
// gain k (image_gain) times the guide-weighted mean luminance squared, which a region
// noisier than the frame's median underestimates: the cap errs towards
// filtering less. One invocation per pixel.
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
  // The squared residuals of the taps on p's surface (geometry weight at
  // least 1/2, p itself always), kept sorted by insertion.
  float r2[25];
  int n = 0;
  float mean = 0.0, weight = 0.0, r2_sum = 0.0;
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
      r2_sum += sq.w;
      int k = n++;
      for (; k > 0 && r2[k - 1] > sq.w; --k) r2[k] = r2[k - 1];
      r2[k] = sq.w;
    }
  const float gain = uintBitsToFloat(histogram.data[GAIN_BINS]);
  const float m = mean / weight;
  const float cap = DN_PARAM_VALUE(image, noise_cap);
  // The median over its chi-square ratio (image_gain.glsl): a firefly or
  // an edge among the taps, a minority, does not move it.
  const float local = DN_PARAM_VALUE(image, noise_mean) != 0.0 ? r2_sum / float(n) / 1.25
                                                               : r2[n / 2] * DN_GAIN_MEDIAN_TO_MEAN / 1.25;
  noisy.data[pi] = vec4(sp.rgb, cap > 0.0 ? min(local, cap * gain * m * m) : local);
}
