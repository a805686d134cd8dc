#version 450
// image_gain: mode clear zeroes the histogram (GAIN_BINS invocations);
// mode median (one invocation) finds the median of t over the binned pixels,
// interpolated linearly within its bin, and stores the frame's noise gain
// k = median / 0.4549 (image_gain.glsl): the noise variance of a pixel is
// modelled as k times its squared local mean luminance, the multiplicative
// noise of Monte Carlo sampling at a uniform sample count. A median, so the
// pixels whose residual is structure (edges, fine texture, reflections), a
// minority, do not move it. 0 when no pixel was binned.
//
// Resources: image_gain.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "pass.glsl"
#include "generated/passes/image_gain.pass"
#include "image_gain.glsl"

void main() {
  const uint t = dn_invocation_index();
  if (MODE == DN_MODE_clear) {
    if (t <= GAIN_BINS) histogram.data[t] = 0u;
    return;
  }
  if (t != 0u) return;
  uint total = 0u;
  for (uint b = 0u; b < GAIN_BINS; ++b) total += histogram.data[b];
  float k = 0.0;
  if (total > 0u) {
    const float half_count = 0.5 * float(total);
    float below = 0.0;
    uint b = 0u;
    for (; b < GAIN_BINS - 1u && below + float(histogram.data[b]) < half_count; ++b) below += float(histogram.data[b]);
    const float within = histogram.data[b] > 0u ? (half_count - below) / float(histogram.data[b]) : 0.5;
    const float log2_median = DN_GAIN_LOG2_MIN + (float(b) + within) / DN_GAIN_BINS_PER_OCTAVE;
    k = exp2(log2_median) * DN_GAIN_MEDIAN_TO_MEAN;
  }
  histogram.data[GAIN_BINS] = floatBitsToUint(k);
}
