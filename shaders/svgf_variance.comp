#version 450
// svgf_variance: per-pixel luminance variance from the temporal moments
// (docs/pipelines.md, "svgf in detail", 2). One invocation per pixel.
//   background: 0
//   len >= 4:   max(0, m2 - m1^2)
//   len < 4:    Falcor's 7x7 estimate: moments averaged over the foreground
//               pixels q of the 7x7 box with weight 1 for p itself and
//               exp(-|z_p - z_q| / (phi_depth * max(dz_p, 1e-8) * 3 * |q - p|)
//                   - |l_p - l_q| / (phi_colour * l_p + 1e-20)) * max(0, n_p.n_q)^phi_normal
//               else; variance = max(0, m2 - m1^2) * 4 / len.
// The luminance term is relative to l_p here (Falcor divides by phi_colour
// alone, in absolute units), so the filter stays scale-equivariant.
//
// Bindings: 0 FrameConstants, 1 normal, 2 depth, 3 current colour history (reads .a = length, .rgb),
//   4 current aux history (reads m1, m2), 5 illumination (writes .w = variance)
// Specialization: 0 workgroup size, 1 normal is fp16, 2 depth is fp16
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "luminance.glsl"

layout(constant_id = 1) const bool NORMAL_HALF = false;
layout(constant_id = 2) const bool DEPTH_HALF = false;

layout(std430, set = 0, binding = 1) readonly buffer NormalPlane { uint data[]; } normal;
layout(std430, set = 0, binding = 2) readonly buffer DepthPlane { uint data[]; } depth;
layout(std430, set = 0, binding = 3) readonly buffer CurColour { vec4 data[]; } cur_colour;
layout(std430, set = 0, binding = 4) readonly buffer CurAux { uvec4 data[]; } cur_aux;
layout(std430, set = 0, binding = 5) buffer Illumination { vec4 data[]; } illum;

#include "svgf.glsl"

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  ivec2 size = ivec2(frame.size.xy);
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  float z = dn_svgf_depth(p);
  if (!dn_is_foreground(z)) {
    illum.data[p].w = 0.0;
    return;
  }
  vec4 h = cur_colour.data[p];
  vec2 m = uintBitsToFloat(cur_aux.data[p].xy);
  float len = h.a;
  if (len >= 4.0) {
    illum.data[p].w = max(0.0, m.y - m.x * m.x);
    return;
  }
  vec3 n = dn_svgf_normal(p);
  float inv_phi_z = 1.0 / (DN_PARAM_VALUE(DN_P_svgf_phi_depth) * max(dn_svgf_gradients(pos, z, n).x, 1e-8) * 3.0);
  float l = dn_luminance(h.rgb);
  float inv_phi_l = 1.0 / (DN_PARAM_VALUE(DN_P_svgf_phi_colour) * l + DN_SVGF_LUMINANCE_EPS);
  float phi_n = DN_PARAM_VALUE(DN_P_svgf_phi_normal);
  vec2 sum_m = m;
  float sum_w = 1.0;
  for (int yy = -3; yy <= 3; ++yy) {
    for (int xx = -3; xx <= 3; ++xx) {
      if (xx == 0 && yy == 0) continue;
      ivec2 q = pos + ivec2(xx, yy);
      if (q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) continue;
      uint qi = uint(q.y) * uint(size.x) + uint(q.x);
      float zq = dn_svgf_depth(qi);
      if (!dn_is_foreground(zq)) continue;
      float cos_n = dot(n, dn_svgf_normal(qi));
      if (!(cos_n > 0.0)) continue;  // normal weight 0
      float w_z = abs(z - zq) * inv_phi_z * inversesqrt(float(xx * xx + yy * yy));
      float w_l = abs(l - dn_luminance(cur_colour.data[qi].rgb)) * inv_phi_l;
      float w = exp2(phi_n * log2(cos_n) - (w_z + w_l) * 1.4426950408889634);
      sum_m += w * uintBitsToFloat(cur_aux.data[qi].xy);
      sum_w += w;
    }
  }
  m = sum_m / sum_w;
  illum.data[p].w = max(0.0, m.y - m.x * m.x) * 4.0 / len;
}
