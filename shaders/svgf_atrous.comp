#version 450
// svgf_atrous: one edge-stopping a-trous iteration (docs/pipelines.md,
// "svgf in detail", 3); one pipeline specialization per iteration (STEP).
// One invocation per pixel. For a foreground pixel p with (c_p, v_p):
//   g   = 3x3 gaussian {1/4, 1/2, 1/4}^2 of the variance over the pixels inside
//         the image, renormalised
//   phi_l = phi_colour * sqrt(g + 1e-20)
//   taps q = p + STEP * (i, j), i, j in -2..2, inside and foreground, q != p:
//     w_q = h(i) h(j) * exp(-|z_p - z_q| / (phi_depth * max(dz_p, 1e-8) * STEP * |(i, j)|)
//                           - |l_p - l_q| / phi_l) * max(0, n_p.n_q)^phi_normal
//     with h = {1/6, 2/3, 1, 2/3, 1/6} (the B3 kernel {1/16, 1/4, 3/8, 1/4, 1/16} / (3/8))
//   p itself has weight 1; c = sum w c / sum w, v = sum w^2 v / (sum w)^2.
// Background pixels are copied. With FEEDBACK the result's rgb also becomes
// the colour history (length kept).
//
// Bindings: 0 FrameConstants, 1 normal, 2 depth, 3 source illumination,
//   4 destination illumination, 5 current colour history (writes .rgb if FEEDBACK)
// Specialization: 0 workgroup size, 1 normal is fp16, 2 depth is fp16, 3 step, 4 feedback
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "luminance.glsl"

layout(constant_id = 1) const bool NORMAL_HALF = false;
layout(constant_id = 2) const bool DEPTH_HALF = false;
layout(constant_id = 3) const int STEP = 1;
layout(constant_id = 4) const bool FEEDBACK = false;

layout(std430, set = 0, binding = 1) readonly buffer NormalPlane { uint data[]; } normal;
layout(std430, set = 0, binding = 2) readonly buffer DepthPlane { uint data[]; } depth;
layout(std430, set = 0, binding = 3) readonly buffer Source { vec4 data[]; } src;
layout(std430, set = 0, binding = 4) writeonly buffer Destination { vec4 data[]; } dst;
layout(std430, set = 0, binding = 5) writeonly buffer CurColour { vec4 data[]; } cur_colour;

#include "svgf.glsl"

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  ivec2 size = ivec2(frame.size.xy);
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  vec4 centre = src.data[p];
  float z = dn_svgf_depth(p);
  if (!dn_is_foreground(z)) {
    dst.data[p] = centre;
    if (FEEDBACK) cur_colour.data[p].rgb = centre.rgb;
    return;
  }
  vec3 n = dn_svgf_normal(p);

  const float g[3] = float[3](0.25, 0.5, 0.25);
  float gv = 0.0, gw = 0.0;
  for (int yy = -1; yy <= 1; ++yy) {
    for (int xx = -1; xx <= 1; ++xx) {
      ivec2 q = pos + ivec2(xx, yy);
      if (q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) continue;
      float k = g[xx + 1] * g[yy + 1];
      gv += k * src.data[uint(q.y) * uint(size.x) + uint(q.x)].w;
      gw += k;
    }
  }
  float inv_phi_l = 1.0 / (DN_PARAM_VALUE(DN_P_svgf_phi_colour) * sqrt(gv / gw + DN_SVGF_VARIANCE_EPS));
  float inv_phi_z = 1.0 / (DN_PARAM_VALUE(DN_P_svgf_phi_depth) * max(dn_svgf_gradients(pos, z, n).x, 1e-8) * float(STEP));
  float phi_n = DN_PARAM_VALUE(DN_P_svgf_phi_normal);
  float l = dn_luminance(centre.rgb);

  const float h[5] = float[5](1.0 / 6.0, 2.0 / 3.0, 1.0, 2.0 / 3.0, 1.0 / 6.0);
  vec3 sum_c = centre.rgb;
  float sum_v = centre.w;
  float sum_w = 1.0;
  for (int yy = -2; yy <= 2; ++yy) {
    for (int xx = -2; xx <= 2; ++xx) {
      if (xx == 0 && yy == 0) continue;
      ivec2 q = pos + STEP * ivec2(xx, yy);
      if (q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) continue;
      uint qi = uint(q.y) * uint(size.x) + uint(q.x);
      float zq = dn_svgf_depth(qi);
      if (!dn_is_foreground(zq)) continue;
      float cos_n = dot(n, dn_svgf_normal(qi));
      if (!(cos_n > 0.0)) continue;  // normal weight 0
      vec4 s = src.data[qi];
      float w_z = abs(z - zq) * inv_phi_z * inversesqrt(float(xx * xx + yy * yy));
      float w_l = abs(l - dn_luminance(s.rgb)) * inv_phi_l;
      // exp(-w_z - w_l) * cos_n^phi_normal with one exp2 and one log2
      float w = h[xx + 2] * h[yy + 2] * exp2(phi_n * log2(cos_n) - (w_z + w_l) * 1.4426950408889634);
      sum_c += w * s.rgb;
      sum_v += w * w * s.w;
      sum_w += w;
    }
  }
  vec4 result = vec4(sum_c / sum_w, sum_v / (sum_w * sum_w));
  dst.data[p] = result;
  if (FEEDBACK) cur_colour.data[p].rgb = result.rgb;
}
