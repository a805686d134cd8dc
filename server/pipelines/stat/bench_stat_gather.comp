#version 450
// bench_stat_gather (bench/stat_gather_bench.cpp): stat's disc gather
// (stat_gather.glsl, the decisions of stat_filter) over fp32 vec4 buffers, in
// 8x8 workgroups, reading the taps either straight from the buffers (plain
// loads: albedo, normal and the raw mean only for members, as stat_filter)
// or from a shared-memory tile of all five loaded once per workgroup
// (TILED; radius <= APRON). Taps outside the grid are skipped in both. Not
// used by any pipeline.
//
// Push constants (grid2d.glsl): size = source = the grid; args.x = radius,
// args.yzw = ks, ka, kn (float bits; -1 / (2 sigma^2)).
#extension GL_GOOGLE_include_directive : require
#include "grid2d.glsl"
#include "inside.glsl"
#include "pass.glsl"
#include "generated/passes/bench_stat_gather.pass"

// One table (alpha): the benchmark tests no pair as still.
float dn_stat_t_squared(uint nu, bool still) { return t_squared.data[min(nu, 1024u) - 1u]; }
#include "stat_gather.glsl"

struct Tap {
  vec4 theta, variance, raw, albedo, normal;
};
#define DN_TILE_APRON APRON
#define DN_TILE_T Tap
#include "tile.glsl"

Tap dn_tile_fetch(ivec2 p) {
  uint i = dn_grid_index(uvec2(p), dn_grid.size);
  return Tap(theta.data[i], variance.data[i], raw.data[i], albedo.data[i], normal.data[i]);
}

void main() {
  if (TILED) dn_tile_load(dn_grid.size);
  const uvec2 p = dn_pixel();
  if (!dn_in_grid(p)) return;
  const uint pi = dn_grid_index(p, dn_grid.size);
  const int r = TILED ? min(int(dn_arg_radius()), int(APRON)) : int(dn_arg_radius());
  DnStatKernel k = DnStatKernel(dn_arg_ks(), dn_arg_ka(), dn_arg_kn(), true, false, 0.0);
  vec4 theta_p = theta.data[pi];
  vec3 var_p = variance.data[pi].rgb, raw_p = raw.data[pi].rgb;
  vec3 albedo_p = albedo.data[pi].rgb, normal_p = normal.data[pi].rgb;
  vec3 sum = vec3(0.0);
  float weight_sum = 1.0;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      int d2xy = dx * dx + dy * dy;
      ivec2 q = ivec2(p) + ivec2(dx, dy);
      if (d2xy > r * r || d2xy == 0 || !dn_inside(q, dn_grid.size))
        continue;
      if (TILED) {
        Tap t = dn_tile_at(ivec2(dx, dy));
        if (dn_stat_membership(theta_p, var_p, t.theta, t.variance.rgb, k, false) == 0.0) continue;
        float w = dn_stat_base_weight(d2xy, albedo_p - t.albedo.rgb, normal_p - t.normal.rgb, k);
        sum += w * (t.raw.rgb - raw_p);
        weight_sum += w;
      } else {
        uint qi = dn_grid_index(uvec2(q), dn_grid.size);
        if (dn_stat_membership(theta_p, var_p, theta.data[qi], variance.data[qi].rgb, k, false) == 0.0) continue;
        float w = dn_stat_base_weight(d2xy, albedo_p - albedo.data[qi].rgb, normal_p - normal.data[qi].rgb, k);
        sum += w * (raw.data[qi].rgb - raw_p);
        weight_sum += w;
      }
    }
  }
  result.data[pi] = vec4(raw_p + sum / weight_sum, weight_sum);
}
