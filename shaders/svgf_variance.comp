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
// Register blocking as in svgf_atrous.comp: one invocation handles the
// BLOCK x BLOCK pixels base + (i, j), base = BLOCK * (ix, iy) over a
// ceil(W / BLOCK) x ceil(H / BLOCK) grid, and loads their (BLOCK + 6)^2
// window once when any of them needs the 7x7 estimate.
//
// Resources: passes/svgf_variance.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "frame.glsl"
#include "sanitize.glsl"
#include "luminance.glsl"
#include "svgf_guards.glsl"
#include "pass.glsl"
#include "passes/svgf_variance.pass"
#include "svgf_joint.glsl"

#define B BLOCK  // a macro, not a const alias: the SPIR-V keeps the declared name BLOCK

const int WIN = BLOCK + 6;

// The samples the temporal colour averages (variance_of_mean): its first
// 1/alpha frames are a true mean of `len` samples, after that an exponential
// average whose variance is alpha / (2 - alpha) of a sample's; 1 when off.
// Signal s's alpha: reflect's alpha_specular for the last with SPECULAR_ALPHA.
float samples_averaged(float len, int s) {
  if (DN_PARAM_VALUE(svgf, variance_of_mean) == 0.0) return 1.0;
  float a = DN_SVGF_ALPHA_OF(SPECULAR_ALPHA && dn_last_signal(s));
  return a > 0.0 ? clamp(len, 1.0, (2.0 - a) / a) : max(len, 1.0);
}

vec3 signal_colour(int s, uint i) { return s == 0 ? illum.data[i].rgb : illum2.data[i].rgb; }

void main() {
  ivec2 size = ivec2(frame.size.xy);
  int nx = (size.x + B - 1) / B;
  uint inv = dn_invocation_index();
  ivec2 base = B * ivec2(int(inv % uint(nx)), int(inv / uint(nx)));
  if (base.y >= size.y) return;

  float phi_n = DN_PARAM_VALUE(svgf, phi_normal);
  float phi_z = DN_PARAM_VALUE(svgf, phi_depth) * 3.0;
  float phi_c = DN_PARAM_VALUE(svgf, phi_colour);
  // Per guide g at [g * B * B + k]: geometry; per signal s at [s * B * B + k].
  float cz[NS * B * B], ipz[NS * B * B];
  vec3 cn[NS * B * B];
  float cl[NS * B * B], len[NS * B * B], var[NS * B * B], sw[NS * B * B];
  vec2 sm[NS * B * B];
  bool inside[B * B], act[NS * B * B];
  bool isolated[NS * B * B];  // every 3x3 foreground neighbour below half of p's luminance
  bool any_act = false;
  [[unroll]] for (int j = 0; j < B; ++j) {
    [[unroll]] for (int i = 0; i < B; ++i) {
      int k = j * B + i;
      ivec2 p = base + ivec2(i, j);
      inside[k] = p.x < size.x && p.y < size.y;
      ivec2 pc = min(p, size - 1);
      uint pi = uint(pc.y) * uint(size.x) + uint(pc.x);
      uvec4 gds[2];
      [[unroll]] for (int s = 0; s < NS; ++s) {
        if (s > 0 && dn_guide_of(s) == 0) continue;
        int g = dn_guide_of(s), gk = g * B * B + k;
        gds[g] = dn_guide_load(g, pi);
        cz[gk] = uintBitsToFloat(gds[g].x);
        cn[gk] = dn_svgf_unpack_normal(gds[g].y);
        ipz[gk] = 1.0 / (phi_z * max(uintBitsToFloat(gds[g].z), 1e-8));
      }
      [[unroll]] for (int s = 0; s < NS; ++s) {
        int g = dn_guide_of(s), gk = g * B * B + k, sk = s * B * B + k;
        uvec4 gd = gds[g];
        vec4 t = dn_temporal_load(s, pi);
        float gz = cz[gk];
        len[sk] = t.z;
        // No data (a foreground pixel of length 0: only a MASKED reprojection
        // makes one): no history depth, so the next frame reprojects nothing from it.
        bool no_data = gz != 0.0 && t.z == 0.0;
        if (inside[k]) {
          vec4 colour = vec4(signal_colour(s, pi), t.z);
          uvec4 aux = uvec4(floatBitsToUint(t.xy), floatBitsToUint(no_data ? 0.0 : max(gz, 0.0)), gd.y);
          if (s == 0) {
            colour_history.data[pi] = colour;
            aux_history.data[pi] = aux;
          } else {
            colour_history2.data[pi] = colour;
            aux_history2.data[pi] = aux;
          }
        }
        // background 0; len >= 4: from the moments; else the 7x7 estimate
        // (without a normal no neighbour is taken: act false, own moments);
        // no data: DN_SVGF_NO_DATA.
        var[sk] = gz == 0.0 ? 0.0 : no_data ? DN_SVGF_NO_DATA : max(0.0, t.y - t.x * t.x);
        act[sk] = SPATIAL_ESTIMATE && inside[k] && gz > 0.0 && t.z < 4.0 && !no_data;
        any_act = any_act || act[sk];
        cl[sk] = t.w;
        sm[sk] = t.xy;  // p itself, weight 1
        sw[sk] = 1.0;
        isolated[sk] = true;
        // A loop of no iterations where p is not young, not an if: see below.
        int neighbours = act[sk] ? 9 : 0;
        [[dont_unroll]] for (int o = 0; o < neighbours; ++o) {
          int xx = o % 3 - 1, yy = o / 3 - 1;
          ivec2 q = p + ivec2(xx, yy);
          if ((xx == 0 && yy == 0) || any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
          uint qi = uint(q.y) * uint(size.x) + uint(q.x);
          if (uintBitsToFloat(dn_guide_load(g, qi).x) > 0.0 && dn_temporal_load(s, qi).w >= 0.5 * t.w)
            isolated[sk] = false;
        }
      }
    }
  }
  // The 7x7 estimate, row by row in a loop of no rows where no block pixel
  // is young. llvmpipe (Mesa 22.3) runs the body of an if whatever its
  // condition, with the lanes masked (measured: the window behind an
  // always-false uniform if cost 18.2 ms at 640x360, removed 2.5 ms), but it
  // leaves a loop after one masked iteration once no lane is in it, so
  // without young pixels this costs one row of the window, not eight. The
  // rows are not unrolled, so which taps a row gives a block pixel is
  // decided per row: the same taps in the same order, but the output is no
  // longer bit-identical to the unrolled window's (last-bit differences in
  // the compiled arithmetic; the CPU-reference comparisons are unchanged).
  int rows = any_act ? WIN : 0;
  {
    [[dont_unroll]] for (int r = 0; r < rows; ++r) {
      [[unroll]] for (int c = 0; c < WIN; ++c) {
        ivec2 q = base + ivec2(c - 3, r - 3);
        ivec2 qc = clamp(q, ivec2(0), size - 1);
        uint qi = uint(qc.y) * uint(size.x) + uint(qc.x);
        // The tap's geometry per guide, loaded and decoded once for every
        // signal and block pixel that takes it.
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
        vec4 tq[NS];
        [[unroll]] for (int s = 0; s < NS; ++s) tq[s] = dn_temporal_load(s, qi);
        [[unroll]] for (int j = 0; j < B; ++j) {
          int dy = r - j - 3;
          bool row_tap = dy >= -3 && dy <= 3;
          [[unroll]] for (int i = 0; i < B; ++i) {
            int dx = c - i - 3;
            if (dx < -3 || dx > 3) continue;
            int k = j * B + i;
            bool tap = row_tap && !(dx == 0 && dy == 0);  // p itself: added above
            [[unroll]] for (int s = 0; s < NS; ++s) {
              int g = dn_guide_of(s), gk = g * B * B + k, sk = s * B * B + k;
              // The same expressions for every signal of a guide: the
              // geometric terms are computed once, and each signal's
              // weights are bit for bit its weights alone.
              float cos_n = dot(cn[gk], nq[g]);
              float w_z = abs(cz[gk] - zq[g]) * ipz[gk] * inversesqrt(float(max(dx * dx + dy * dy, 1)));
              float relative_to = isolated[sk] ? max(cl[sk], tq[s].w) : min(cl[sk], tq[s].w);
              float w_l = abs(cl[sk] - tq[s].w) / (phi_c * relative_to + DN_SVGF_LUMINANCE_EPS);
              float w = exp2(phi_n * log2(max(cos_n, 1e-37)) - (w_z + w_l) * 1.4426950408889634);
              w = (tap && act[sk] && tap_ok[g] && cos_n > 0.0) ? w : 0.0;
              sm[sk] += w * tq[s].xy;
              sw[sk] += w;
            }
          }
        }
      }
    }
  }
  [[unroll]] for (int s = 0; s < NS; ++s) {
    [[unroll]] for (int j = 0; j < B; ++j) {
      [[unroll]] for (int i = 0; i < B; ++i) {
        int k = j * B + i, sk = s * B * B + k, gk = dn_guide_of(s) * B * B + k;
        if (!inside[k]) continue;
        ivec2 p = base + ivec2(i, j);
        uint pi = uint(p.y) * uint(size.x) + uint(p.x);
        float v = var[sk];
        if (SPATIAL_ESTIMATE && cz[gk] != 0.0 && len[sk] < 4.0 && v != DN_SVGF_NO_DATA) {
          vec2 m = sm[sk] / sw[sk];
          v = max(0.0, m.y - m.x * m.x) * 4.0 / len[sk];
        }
        v = v == DN_SVGF_NO_DATA ? v : v / samples_averaged(len[sk], s);
        if (s == 0) illum.data[pi].w = v;
        else illum2.data[pi].w = v;
      }
    }
  }
}
