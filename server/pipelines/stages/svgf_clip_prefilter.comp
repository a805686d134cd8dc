#version 450
// svgf_clip_prefilter: the 7x7 Gaussian prefilter of the current signal that
// history clipping takes its box from (paper 001 §4.2.3: clipping to the
// min/max of the raw 1-spp neighbourhood would follow its noise). Weights:
// the binomial {1, 6, 15, 20, 15, 6, 1} / 64 per axis (sigma 1.22 px), over
// the foreground pixels inside the image, renormalised. One invocation per
// pixel; three specializations (MODE): the demodulated current signal once
// per pixel (read again by the two filter passes and by svgf_reproject's
// clip box and rejection test: one texel fetch per tap instead of the
// planes' words, its sanitizing and its division), then separable rows and
// columns.
//
// Resources: svgf_clip_prefilter.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "svgf_guards.glsl"
#include "inside.glsl"
#include "pass.glsl"
#include "generated/passes/svgf_clip_prefilter.pass"

#include "svgf_signal.glsl"

const float kBinomial[7] = float[7](1.0, 6.0, 15.0, 20.0, 15.0, 6.0, 1.0);

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  if (MODE == DN_MODE_current) {
    dst.data[p] = vec4(dn_svgf_current(p), dn_is_foreground(DN_LOAD1(depth, p)) ? 1.0 : 0.0);
    return;
  }
  bool vertical = MODE == DN_MODE_vertical;
  ivec2 size = ivec2(frame.size.xy);
  ivec2 pos = ivec2(int(p % frame.size.x), int(p / frame.size.x));
  vec4 sum = vec4(0.0);
  for (int t = -3; t <= 3; ++t) {
    ivec2 q = vertical ? pos + ivec2(0, t) : pos + ivec2(t, 0);
    if (!dn_inside(q, uvec2(size))) continue;
    float w = kBinomial[t + 3];
    vec4 s = src_at(uint(q.y) * frame.size.x + uint(q.x));
    // Horizontal: s is (current, foreground), and a background tap adds
    // nothing (a select, not a product: its current may be any value);
    // vertical: s is (sum w c, sum w).
    if (vertical) sum += w * s;
    else sum += s.w > 0.0 ? vec4(w * s.rgb, w) : vec4(0.0);
  }
  if (vertical) dst.data[p] = sum.w > 0.0 ? vec4(sum.rgb / sum.w, 1.0) : vec4(0.0);
  else dst.data[p] = sum;
}
