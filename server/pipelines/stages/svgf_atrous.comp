#version 450
// svgf_atrous: one edge-stopping a-trous iteration (docs/pipelines.md,
// "svgf in detail", 3); one pipeline specialization per iteration (STEP).
// For a foreground pixel p with (c_p, v_p):
//   g   = 3x3 gaussian {1/4, 1/2, 1/4}^2 of the variance over the pixels q
//         inside the image whose luminance step to p their own noise explains,
//         |l_p - l_q| <= 3 sqrt(v_q) (the HDR step rule; p always), renormalised
//   phi_l = phi_colour * sqrt(g + 1e-20), times 8 - min(7, len - 1) with
//         LUMINANCE_RAMP (luminance_ramp; paper 001 Eq. 8; len the history length, temporal .z)
//   taps q = p + STEP * (i, j), i, j in -2..2, inside and foreground, q != p:
//     w_q = h(i) h(j) * exp(-|z_p - z_q| / (phi_depth * max(dz_p, 1e-8) * STEP * |(i, j)|)
//                           - |l_p - l_q| / phi_l) * max(0, n_p.n_q)^phi_normal
//     with h = {1/6, 2/3, 1, 2/3, 1/6} (the B3 kernel {1/16, 1/4, 3/8, 1/4, 1/16} / (3/8))
//     times exp(-(i^2 + j^2) / (2 sigma_p^2)) with SPATIAL_BANDWIDTH and
//     sigma_p = bandwidth[p] > 0 (reflect's Eq. 6; in steps, so the same
//     fraction of every iteration's footprint)
//   p itself has weight 1; c = sum w c / sum w, v = sum w^2 v / (sum w)^2
//   (v_p unchanged without propagate_variance: paper 001 §6).
// KERNEL_RADIUS 1 (progressive, paper 004): taps i, j in -1..1 with
// h = {1/2, 1, 1/2} (the 3x3 {1/4, 1/2, 1/4}^2 / (1/2)^2). LUMINANCE_VARIANCE:
// phi_l's place is taken by sigma_luminance * g + epsilon_luminance (paper
// 004's variance form). AGE_GATED_LUMINANCE: no luminance term while p's
// length < luminance_min_age, and no FEEDBACK write (its history stays the
// unfiltered accumulation). MASKED: FEEDBACK writes only where sample_count > 0. A pixel without data (variance
// DN_SVGF_NO_DATA, MASKED chains) is no tap and no variance-prefilter tap; as
// p it starts from weight 0 without a luminance term, and stays without data
// when no tap has any.
// Background pixels (and pixels without a normal, which take no tap) are
// copied. With FEEDBACK the result's rgb also becomes the colour history
// (length kept). Depth, dz and the (octahedral, unit) normal come from the
// guide written by svgf_reproject.
//
// SIGNALS 2 (split diffuse and specular, svgf_chain's joint chain): both
// signals in one pass, each exactly as it would be filtered alone (its own
// src, variance, luminance weights, temporal length and history), sharing the
// guide's loads and the geometric terms of every tap, as NRD filters diffuse
// and specular together; SECOND_GUIDE gives the second its own guide (and
// geometric weights). CLASS_EDGES and SPATIAL_BANDWIDTH are the last signal's.
//
// Register blocking: one invocation filters a BLOCK x BLOCK set of pixels
// spaced STEP apart, base + STEP * (i, j). Their taps form one
// (BLOCK + 4)^2 window on the same STEP lattice, and each window pixel is
// loaded and decoded once for all the block pixels it is a tap of (on
// lavapipe every storage-buffer word read is a per-lane scalar load, so this
// is what the pass costs). Invocation (ix, iy) of a grid of
// (ceil(W / (STEP * BLOCK)) * STEP) x (ceil(H / (STEP * BLOCK)) * STEP):
// base = (ix / STEP * STEP * BLOCK + ix % STEP, same in y).
//
// Resources: svgf_atrous.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "luminance.glsl"
#include "svgf_guards.glsl"
#include "reproject.glsl"
#include "pass.glsl"
#include "generated/passes/svgf_atrous.pass"
#include "svgf_joint.glsl"

// DISPLAY_FILL's sources: foreground pixels with a normal and data, of the
// signal dn_fill_signal (set before each ring search).
int dn_fill_signal = 0;

#define B BLOCK  // a macro, not a const alias: the SPIR-V keeps the declared name BLOCK
#define R KERNEL_RADIUS
const int WIN = BLOCK + 2 * KERNEL_RADIUS;

// Signal s's illumination in (svgf_joint.glsl's rule: s a loop constant, or NS 1).
vec4 signal_src(int s, uint i) { return s == 0 || NS == 1 ? src_at(i) : src2_at(i); }

bool dn_fill_source(ivec2 q, out vec3 value) {
  uint qi = uint(q.y) * frame.size.x + uint(q.x);
  vec4 s = signal_src(dn_fill_signal, qi);
  value = s.rgb;
  return uintBitsToFloat(dn_guide_load(dn_guide_of(dn_fill_signal), qi).x) > 0.0 && s.w != DN_SVGF_NO_DATA;
}
#include "ring_fill.glsl"

// The kernel's tap weight at offset i (-R..R) relative to the centre's.
float kernel_tap(int i) {
  const float b3[5] = float[5](1.0 / 6.0, 2.0 / 3.0, 1.0, 2.0 / 3.0, 1.0 / 6.0);
  const float b1[3] = float[3](0.5, 1.0, 0.5);
  return R == 2 ? b3[i + 2] : b1[i + 1];
}

// The normal weight max(0, cos)^phi_normal as exp2(normal_log2) *
// normal_power (cos > 0; the caller zeroes the weight elsewhere): the first
// without NORMAL_POWER, the second, k squarings, with it.
float normal_log2(float cos_n, float phi_n) { return NORMAL_POWER >= 0 ? 0.0 : phi_n * log2(max(cos_n, 1e-37)); }
float normal_power(float cos_n) {
  float c = max(cos_n, 0.0);
  [[unroll]] for (int i = 0; i < max(NORMAL_POWER, 0); ++i) c *= c;
  return NORMAL_POWER >= 0 ? c : 1.0;
}

void main() {
  ivec2 size = ivec2(frame.size.xy);
  int span = STEP * B;
  int nx = (size.x + span - 1) / span * STEP;
  int ny = (size.y + span - 1) / span * STEP;
  uint inv = dn_invocation_index();
  int ix = int(inv % uint(nx)), iy = int(inv / uint(nx));
  if (iy >= ny) return;
  ivec2 base = ivec2(ix / STEP * span + ix % STEP, iy / STEP * span + iy % STEP);

  float phi_n = DN_PARAM_VALUE(svgf, phi_normal);
  float phi_c = DN_PARAM_VALUE(svgf, phi_colour);
  float phi_z = DN_PARAM_VALUE(svgf, phi_depth) * float(STEP);
  bool propagate = DN_PARAM_VALUE(svgf, propagate_variance) != 0.0;
  float sigma_l = DN_PARAM_VALUE(atrous, sigma_luminance);
  float eps_l = DN_PARAM_VALUE(atrous, epsilon_luminance);
  float min_age = DN_PARAM_VALUE(atrous, luminance_min_age);
  float ramp_in = DN_PARAM_VALUE(atrous, luminance_ramp_in);

  // Block pixels' centre data: per guide g at [g * B * B + k] (geometry),
  // per signal s at [s * B * B + k] (colour and weights).
  float cz[NS * B * B], ipz[NS * B * B];
  vec3 cn[NS * B * B];
  bool act[NS * B * B];
  uint ccls[NS * B * B];  // CLASS_EDGES: p's guide .w
  float cl[NS * B * B], ipl[NS * B * B];
  vec3 sc[NS * B * B];
  float sv[NS * B * B], sw[NS * B * B];
  float isig[B * B];  // SPATIAL_BANDWIDTH (last signal): 1 / (2 sigma_p^2), 0 without
  [[unroll]] for (int j = 0; j < B; ++j) {
    [[unroll]] for (int i = 0; i < B; ++i) {
      int k = j * B + i;
      ivec2 p = base + STEP * ivec2(i, j);
      ivec2 pc = min(p, size - 1);
      uint pi = uint(pc.y) * uint(size.x) + uint(pc.x);
      [[unroll]] for (int s = 0; s < NS; ++s) {
        if (s > 0 && dn_guide_of(s) == 0) continue;
        int gk = dn_guide_of(s) * B * B + k;
        uvec4 gd = dn_guide_load(dn_guide_of(s), pi);
        ccls[gk] = gd.w;
        cz[gk] = uintBitsToFloat(gd.x);
        act[gk] = p.x < size.x && p.y < size.y && cz[gk] > 0.0;
        cn[gk] = dn_svgf_unpack_normal(gd.y);
        ipz[gk] = act[gk] ? 1.0 / (phi_z * max(uintBitsToFloat(gd.z), 1e-8)) : 0.0;
      }
      isig[k] = 0.0;
      if (SPATIAL_BANDWIDTH) {
        float sigma = bandwidth.data[pi];
        isig[k] = sigma > 0.0 ? 0.5 / (sigma * sigma) : 0.0;
      }
      [[unroll]] for (int s = 0; s < NS; ++s) {
        int sk = s * B * B + k, gk = dn_guide_of(s) * B * B + k;
        vec4 cs = signal_src(s, pi);
        // A pixel without data takes its neighbours' (no luminance weight: it
        // has no luminance) and adds nothing of its own.
        bool has_data = cs.w != DN_SVGF_NO_DATA;
        cl[sk] = dn_luminance(cs.rgb);
        sc[sk] = has_data ? cs.rgb : vec3(0.0);  // p itself, weight 1
        sv[sk] = has_data ? cs.w : 0.0;
        sw[sk] = has_data ? 1.0 : 0.0;
        ipl[sk] = 0.0;
        if (act[gk]) {
          const float g[3] = float[3](0.25, 0.5, 0.25);
          float gv = 0.0, gw = 0.0;
          for (int yy = -1; yy <= 1; ++yy) {
            for (int xx = -1; xx <= 1; ++xx) {
              ivec2 q = p + ivec2(xx, yy);
              if (!dn_inside(q, uvec2(size))) continue;
              // HDR step rule: a neighbour's variance counts only where its
              // own noise explains the luminance step to p.
              vec4 sq = signal_src(s, uint(q.y) * uint(size.x) + uint(q.x));
              bool same = sq.w != DN_SVGF_NO_DATA &&
                          ((xx == 0 && yy == 0) || abs(cl[sk] - dn_luminance(sq.rgb)) <= DN_SVGF_STEP_SIGMAS * sqrt(sq.w));
              float kk = same ? g[xx + 1] * g[yy + 1] : 0.0;
              gv += kk * sq.w;
              gw += kk;
            }
          }
          // The length only where a spec constant says it is used: the fetch
          // cost 0.2-0.4 ms of an iteration's 6.5 at 640x360.
          float len = LUMINANCE_RAMP || AGE_GATED_LUMINANCE ? dn_temporal_load(s, pi).z : 0.0;
          float widen = LUMINANCE_RAMP ? 8.0 - min(7.0, max(len - 1.0, 0.0)) : 1.0;
          // luminance_ramp_in r: the age gate's weight comes in over r samples,
          // bandwidth x 2^r, ..., 2 (switched on at once, the display jumps).
          if (AGE_GATED_LUMINANCE && min_age > 0.0) widen *= exp2(clamp(min_age + ramp_in - len, 0.0, ramp_in));
          float gvar = gw > 0.0 ? gv / gw : 0.0;
          ipl[sk] = LUMINANCE_VARIANCE ? 1.0 / (widen * (sigma_l * gvar + eps_l))
                                       : 1.0 / (phi_c * widen * sqrt(gvar + DN_SVGF_VARIANCE_EPS));
          if (!has_data || (AGE_GATED_LUMINANCE && len < min_age)) ipl[sk] = 0.0;
        }
      }
    }
  }

  [[unroll]] for (int r = 0; r < WIN; ++r) {
    [[unroll]] for (int c = 0; c < WIN; ++c) {
      ivec2 q = base + STEP * ivec2(c - R, r - R);
      ivec2 qc = clamp(q, ivec2(0), size - 1);
      bool inside = q == qc;
      uint qi = uint(qc.y) * uint(size.x) + uint(qc.x);
      // The tap's geometry per guide, loaded and decoded once for every
      // signal and block pixel that takes it.
      float zq[2];
      vec3 nq[2];
      uint qcls[2];
      [[unroll]] for (int s = 0; s < NS; ++s) {
        if (s > 0 && dn_guide_of(s) == 0) continue;
        uvec4 gq = dn_guide_load(dn_guide_of(s), qi);
        zq[dn_guide_of(s)] = uintBitsToFloat(gq.x);
        nq[dn_guide_of(s)] = dn_svgf_unpack_normal(gq.y);
        qcls[dn_guide_of(s)] = gq.w;
      }
      vec4 sq[NS];
      float lq[NS];
      bool tap_ok[NS];
      [[unroll]] for (int s = 0; s < NS; ++s) {
        sq[s] = signal_src(s, qi);
        lq[s] = dn_luminance(sq[s].rgb);
        tap_ok[s] = inside && zq[dn_guide_of(s)] > 0.0 && sq[s].w != DN_SVGF_NO_DATA;
      }
      [[unroll]] for (int j = 0; j < B; ++j) {
        int dy = r - j - R;
        if (dy < -R || dy > R) continue;
        [[unroll]] for (int i = 0; i < B; ++i) {
          int dx = c - i - R;
          if (dx < -R || dx > R) continue;
          int k = j * B + i;
          if (dx == 0 && dy == 0) continue;  // p itself: added above
          [[unroll]] for (int s = 0; s < NS; ++s) {
            int g = dn_guide_of(s), gk = g * B * B + k, sk = s * B * B + k;
            // The geometric terms are the same expressions for every signal
            // of a guide (computed once), so each signal's weights are
            // bit-identical to filtering it alone.
            float cos_n = dot(cn[gk], nq[g]);
            float w_z = abs(cz[gk] - zq[g]) * ipz[gk] * inversesqrt(float(dx * dx + dy * dy));
            float w_l = abs(cl[sk] - lq[s]) * ipl[sk];
            if (SPATIAL_BANDWIDTH && dn_last_signal(s)) w_l += float(dx * dx + dy * dy) * isig[k];
            float w = kernel_tap(dx) * kernel_tap(dy) *
                      exp2(normal_log2(cos_n, phi_n) - (w_z + w_l) * 1.4426950408889634) * normal_power(cos_n);
            bool same_class = !(CLASS_EDGES && dn_last_signal(s)) || qcls[g] == ccls[gk];
            w = (act[gk] && tap_ok[s] && cos_n > 0.0 && same_class) ? w : 0.0;
            sc[sk] += w * sq[s].rgb;
            sv[sk] += propagate ? w * w * sq[s].w : 0.0;
            sw[sk] += w;
          }
        }
      }
    }
  }

  uint fill_mask[NS];  // DISPLAY_FILL: per signal, the block pixels still without data
  [[unroll]] for (int s = 0; s < NS; ++s) {
    fill_mask[s] = 0u;
    [[unroll]] for (int j = 0; j < B; ++j) {
      [[unroll]] for (int i = 0; i < B; ++i) {
        int k = j * B + i, sk = s * B * B + k;
        ivec2 p = base + STEP * ivec2(i, j);
        if (p.x >= size.x || p.y >= size.y) continue;
        uint pi = uint(p.y) * uint(size.x) + uint(p.x);
        // Still no data where neither p nor any tap has any.
        vec4 result = sw[sk] > 0.0 ? vec4(sc[sk] / sw[sk], propagate ? sv[sk] / (sw[sk] * sw[sk]) : sv[sk])
                                   : vec4(0.0, 0.0, 0.0, DN_SVGF_NO_DATA);
        if (DISPLAY_FILL && result.w == DN_SVGF_NO_DATA) fill_mask[s] |= 1u << uint(k);
        if (s == 0) dst.data[pi] = result;
        else dst2.data[pi] = result;
        if (FEEDBACK && (!MASKED || dn_is_sampled(DN_LOAD1(sample_count, pi))) &&
            (!AGE_GATED_LUMINANCE || dn_temporal_load(s, pi).z >= min_age)) {
          if (s == 0) colour_history.data[pi].rgb = result.rgb;
          else colour_history2.data[pi].rgb = result.rgb;
        }
      }
    }
  }
  // DISPLAY_FILL, outside the unrolled block: the ring search is long and
  // rare, and unrolled once per block pixel it made this pass 13x slower.
  if (DISPLAY_FILL) {
    [[dont_unroll]] for (int s = 0; s < NS; ++s) {
      if (fill_mask[s] == 0u) continue;
      dn_fill_signal = s;
      [[dont_unroll]] for (int k = 0; k < B * B; ++k) {
        if ((fill_mask[s] & (1u << uint(k))) == 0u) continue;
        ivec2 p = base + STEP * ivec2(k % B, k / B);
        vec3 fill;
        if (!dn_ring_fill(p, uvec2(size), fill)) continue;
        uint pi = uint(p.y) * uint(size.x) + uint(p.x);
        if (s == 0) dst.data[pi] = vec4(fill, 0.0);
        else dst2.data[pi] = vec4(fill, 0.0);
      }
    }
  }
}
