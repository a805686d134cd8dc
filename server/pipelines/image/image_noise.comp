#version 450
// image_noise: the noise variance of a pixel's demodulated luminance: the
// smaller of two estimates over its 5x5 neighbourhood, each tap weighed by
// how much its guides say it lies on p's surface: the mean of the squared
// residuals (image_prepare's .w) divided by 1.25 (a residual's variance for
// independent noise of equal variance), which structure inflates, and the
// frame's gain k (image_gain) times the squared mean luminance, which a
// region noisier than the frame's median underestimates: the smaller errs
// towards filtering less. One invocation per pixel.
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
  float sum = sp.w, mean = dn_luminance(sp.rgb), weight = 1.0;
  for (int y = -2; y <= 2; ++y)
    for (int x = -2; x <= 2; ++x) {
      const ivec2 q = p + ivec2(x, y);
      if ((x == 0 && y == 0) || any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
      const uint qi = uint(q.y) * uint(size.x) + uint(q.x);
      const float w = dn_image_geometry_weight(gp, guide_at(qi), ap, dn_image_albedo(qi), length(vec2(x, y)));
      const vec4 sq = signal_at(qi);
      sum += w * sq.w;
      mean += w * dn_luminance(sq.rgb);
      weight += w;
    }
  const float gain = uintBitsToFloat(histogram.data[GAIN_BINS]);
  const float m = mean / weight;
  noisy.data[pi] = vec4(sp.rgb, min(sum / (1.25 * weight), gain * m * m));
}
