#version 450
// svgf_variance: per-pixel luminance variance from the temporal moments
// (docs/pipelines.md, "svgf in detail", 2), and the history write-back.
// One invocation per pixel.
//   background: 0
//   len >= 4:   max(0, m2 - m1^2)
//   no data (MASKED chains: length 0 at a foreground pixel): DN_SVGF_NO_DATA
//   len < 4 with SPATIAL_ESTIMATE (else as len >= 4): Falcor's 7x7 estimate: moments averaged over the foreground
//               pixels q of the 7x7 box with weight 1 for p itself and
//               exp(-|z_p - z_q| / (phi_depth * max(dz_p, 1e-8) * 3 * |q - p|)
//                   - |l_p - l_q| / (phi_colour * min(l_p, l_q) + 1e-20)) * max(0, n_p.n_q)^phi_normal
//               else; variance = max(0, m2 - m1^2) * 4 / len.
// The luminance term is relative (Falcor divides by phi_colour alone, in
// absolute units), so the filter stays scale-equivariant, and relative to the
// darker of the two (HDR step rule): a highlight does not average its dark
// surroundings into its variance, nor they it. Except at an isolated bright
// pixel, whose 8 foreground neighbours are all darker than half its
// luminance (a firefly): there the term is relative to the brighter of the
// two, so its variance holds its neighbours' and the a-trous filters it;
// under the HDR step rule its variance was its own single sample's, 0, and
// a firefly went through untouched. A highlight has neighbours like itself
// (a 3x3 one's corner has 3). Isolated dark pixels keep the HDR step rule:
// taking them too blurred the edge of a light. Normals are the guide's
// octahedral snorm16x2 ones (unit length).
// History: this pass runs after every read of the (single-copy) history by
// svgf_reproject, and writes it for the next frame: colour vec4(temporal rgb,
// len) (the feedback a-trous iteration later replaces .rgb) and aux
// uvec4(m1, m2, depth or 0 without normal, packed normal or 0).
//
// SIGNALS 2 (the joint chain, svgf_joint.glsl): split diffuse and specular
// in one pass, each exactly as alone (its own moments, luminance weights,
// length and histories), sharing the guide's loads and the estimate's
// geometric terms unless SECOND_GUIDE.
//
// One invocation per pixel: a young pixel reads its own 7x7 taps (sharing a
// block's window between its pixels cost more than it saved: see main).
//
// Resources: svgf_variance.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "frame.glsl"
#include "sanitize.glsl"
#include "luminance.glsl"
#include "svgf_guards.glsl"
#include "pass.glsl"
#include "generated/passes/svgf_variance.pass"
#include "svgf_joint.glsl"

vec3 signal_colour(int s, uint i) { return s == 0 ? illum.data[i].rgb : illum2.data[i].rgb; }
// Signal s's variance divisor: svgf_reproject's .w (dn_svgf_variance_divisor).
float variance_divisor(int s, uint i) { return s == 0 ? illum.data[i].w : illum2.data[i].w; }

void main() {
  ivec2 size = ivec2(frame.size.xy);
  uint pi = dn_invocation_index();
  if (pi >= uint(size.x) * uint(size.y)) return;
  ivec2 p = ivec2(int(pi % uint(size.x)), int(pi / uint(size.x)));

  float phi_n = DN_PARAM_VALUE(svgf, phi_normal);
  float phi_z = DN_PARAM_VALUE(svgf, phi_depth) * 3.0;
  float phi_c = DN_PARAM_VALUE(svgf, phi_colour);
  // Per guide g: geometry; per signal s: moments, weights and flags.
  float cz[2], ipz[2];
  vec3 cn[2];
  float cl[NS], len[NS], var[NS];
  bool act[NS];
  bool isolated[NS];  // every 3x3 foreground neighbour below half of p's luminance
  uvec4 gds[2];
  [[unroll]] for (int s = 0; s < NS; ++s) {
    if (s > 0 && dn_guide_of(s) == 0) continue;
    int g = dn_guide_of(s);
    gds[g] = dn_guide_load(g, pi);
    cz[g] = uintBitsToFloat(gds[g].x);
    cn[g] = dn_svgf_unpack_normal(gds[g].y);
    ipz[g] = 1.0 / (phi_z * max(uintBitsToFloat(gds[g].z), 1e-8));
  }
  // Signal s's sums of the 7x7 estimate (p itself with weight 1): moments at
  // .xy (s 0) or .zw (s 1), weights at [s]. Vectors, not arrays: see below.
  vec4 moments = vec4(0.0);
  vec2 weights = vec2(1.0);
  [[unroll]] for (int s = 0; s < NS; ++s) {
    int g = dn_guide_of(s);
    vec4 t = dn_temporal_load(s, pi);
    float gz = cz[g];
    len[s] = t.z;
    // No data (a foreground pixel of length 0: only a MASKED reprojection
    // makes one): no history depth, so the next frame reprojects nothing from it.
    // A pixel without a normal leaves its depth negated: no history, but its
    // still mean goes on (svgf_reproject).
    bool no_data = gz != 0.0 && t.z == 0.0;
    vec4 colour = vec4(signal_colour(s, pi), t.z);
    uvec4 aux = uvec4(floatBitsToUint(t.xy), floatBitsToUint(no_data ? 0.0 : gz), gds[g].y);
    if (s == 0) {
      colour_history.data[pi] = colour;
      aux_history.data[pi] = aux;
      moments.xy = t.xy;
    } else {
      colour_history2.data[pi] = colour;
      aux_history2.data[pi] = aux;
      moments.zw = t.xy;
    }
    // background 0; len >= 4: from the moments; else the 7x7 estimate
    // (without a normal no neighbour is taken: act false, own moments);
    // no data: DN_SVGF_NO_DATA.
    var[s] = gz == 0.0 ? 0.0 : no_data ? DN_SVGF_NO_DATA : max(0.0, t.y - t.x * t.x);
    act[s] = SPATIAL_ESTIMATE && gz > 0.0 && t.z < 4.0 && !no_data;
    cl[s] = t.w;
    isolated[s] = true;
    // A loop of no iterations where p is not young, not an if: see below.
    int neighbours = act[s] ? 9 : 0;
    [[dont_unroll]] for (int o = 0; o < neighbours; ++o) {
      int xx = o % 3 - 1, yy = o / 3 - 1;
      ivec2 q = p + ivec2(xx, yy);
      if ((xx == 0 && yy == 0) || any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
      uint qi = uint(q.y) * uint(size.x) + uint(q.x);
      if (uintBitsToFloat(dn_guide_load(g, qi).x) > 0.0 && dn_temporal_load(s, qi).w >= 0.5 * t.w)
        isolated[s] = false;
    }
  }
  // The 7x7 estimate, one tap per iteration of a loop of no iterations where
  // p is not young. llvmpipe (Mesa 22.3) runs the body of an if whatever its
  // condition, with the lanes masked, but leaves a loop after one masked
  // iteration once no lane is in it, so without young pixels this costs one
  // tap. The taps are visited row by row, p itself skipped. (Measured at
  // 640x360 without young pixels: 4.4 ms; the 2x2 block sharing one window,
  // its rows in such a loop and its sums in arrays, 12.2 ms; without the
  // estimate 1.9 ms: docs/pipelines.md, cost model.)
  bool young = act[0] || act[NS - 1];
  int taps = young ? 49 : 0;
  [[dont_unroll]] for (int t = 0; t < taps; ++t) {
    int dx = t % 7 - 3, dy = t / 7 - 3;
    ivec2 q = p + ivec2(dx, dy);
    ivec2 qc = clamp(q, ivec2(0), size - 1);
    uint qi = uint(qc.y) * uint(size.x) + uint(qc.x);
    bool tap = !(dx == 0 && dy == 0);  // p itself: added above
    float dist = inversesqrt(float(max(dx * dx + dy * dy, 1)));
    // The tap's geometry per guide, loaded and decoded once for every signal of it.
    float zq[2];
    vec3 nq[2];
    bool tap_ok[2];
    [[unroll]] for (int s = 0; s < NS; ++s) {
      if (s > 0 && dn_guide_of(s) == 0) continue;
      int g = dn_guide_of(s);
      uvec2 gq = dn_guide_load(g, qi).xy;
      zq[g] = uintBitsToFloat(gq.x);
      tap_ok[g] = q == qc && zq[g] > 0.0;
      nq[g] = dn_svgf_unpack_normal(gq.y);
    }
    [[unroll]] for (int s = 0; s < NS; ++s) {
      int g = dn_guide_of(s);
      vec4 tq = dn_temporal_load(s, qi);
      // The same expressions for every signal of a guide: the geometric
      // terms are computed once, and each signal's weights are bit for bit
      // its weights alone.
      float cos_n = dot(cn[g], nq[g]);
      float w_z = abs(cz[g] - zq[g]) * ipz[g] * dist;
      float relative_to = isolated[s] ? max(cl[s], tq.w) : min(cl[s], tq.w);
      float w_l = abs(cl[s] - tq.w) / (phi_c * relative_to + DN_SVGF_LUMINANCE_EPS);
      float w = exp2(phi_n * log2(max(cos_n, 1e-37)) - (w_z + w_l) * 1.4426950408889634);
      w = (tap && act[s] && tap_ok[g] && cos_n > 0.0) ? w : 0.0;
      if (s == 0) moments.xy += w * tq.xy;
      else moments.zw += w * tq.xy;
      weights[s] += w;
    }
  }
  [[unroll]] for (int s = 0; s < NS; ++s) {
    float v = var[s];
    if (SPATIAL_ESTIMATE && cz[dn_guide_of(s)] != 0.0 && len[s] < 4.0 && v != DN_SVGF_NO_DATA) {
      vec2 m = (s == 0 ? moments.xy : moments.zw) / weights[s];
      v = max(0.0, m.y - m.x * m.x) * 4.0 / len[s];
    }
    v = v == DN_SVGF_NO_DATA ? v : v / variance_divisor(s, pi);
    if (s == 0) illum.data[pi].w = v;
    else illum2.data[pi].w = v;
  }
}
