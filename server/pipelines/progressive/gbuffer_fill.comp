#version 450
// gbuffer_fill: fills the depth and normal of the pixels a sparse G-buffer
// has no data for (progressive's sparse_gbuffer: a ray-traced G-buffer below
// one sample per pixel; paper 004 §5, the 3x3 "3^N pyramid" of Solh and
// AlRegib 2012). Grid passes (grid2d.glsl; args = (level, 3, width, height)):
//   SEED (full grid): level 0 = the planes where sample_count > 0 (sanitized:
//     background depth 0, normal 0), no data elsewhere.
//   PULL (grid = level L >= 1): each element the mean of its 3x3 block's
//     foreground children (normal renormalized), background when its only
//     children with data are background, no data when none has any.
//   PUSH (grid = level L, from the coarsest - 1 down to 0): an element
//     without data takes its parent's (which has data unless the whole frame
//     has none); elements with data are never changed. At level 0 it also
//     writes the filled depth and normal at full resolution, background where
//     the frame had no data at all.
// Resources: gbuffer_fill.pass.
#extension GL_GOOGLE_include_directive : require
#include "grid2d.glsl"
#include "levels.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "pass.glsl"
#include "generated/passes/gbuffer_fill.pass"


void main() {
  const uvec2 p = dn_pixel();
  if (!dn_in_grid(p)) return;
  const uint level = dn_arg_level(), factor = dn_arg_factor();
  const uvec2 size0 = uvec2(dn_arg_width0(), dn_arg_height0());
  const uint here = dn_level_offset(size0, factor, level) + dn_grid_index(p, dn_grid.size);
  if (MODE == DN_MODE_seed) {
    const float z = DN_LOAD1(depth, here);
    const bool fg = dn_is_foreground(z);
    const vec3 n = fg ? dn_sanitize_normal(DN_LOAD3(normal, here)) : vec3(0.0);
    pyramid.data[here] = vec4(n, fg ? z : 0.0);
    valid.data[here] = dn_is_sampled(DN_LOAD1(sample_count, here)) ? 1u : 0u;
    return;
  }
  if (MODE == DN_MODE_pull) {
    const uint fine = dn_level_offset(size0, factor, level - 1u);
    const uvec2 first = dn_level_first_child(p, factor);
    const uvec2 end = min(first + factor, dn_grid.source);
    vec4 sum = vec4(0.0);
    uint foreground = 0u, any = 0u;
    for (uint y = first.y; y < end.y; ++y)
      for (uint x = first.x; x < end.x; ++x) {
        const uint i = fine + dn_grid_index(uvec2(x, y), dn_grid.source);
        if (valid.data[i] == 0u) continue;
        ++any;
        const vec4 v = pyramid.data[i];
        if (v.w > 0.0) {
          sum += v;
          ++foreground;
        }
      }
    vec4 mean = foreground > 0u ? sum / float(foreground) : vec4(0.0);
    if (dot(mean.xyz, mean.xyz) > 0.0) mean.xyz = normalize(mean.xyz);
    pyramid.data[here] = mean;
    valid.data[here] = any > 0u ? 1u : 0u;
    return;
  }
  // PUSH
  if (valid.data[here] == 0u) {
    const uvec2 coarse_size = dn_level_size(size0, factor, level + 1u);
    const uint parent = dn_level_offset(size0, factor, level + 1u) +
                        dn_grid_index(dn_level_parent(p, factor), coarse_size);
    if (valid.data[parent] != 0u) {
      pyramid.data[here] = pyramid.data[parent];
      valid.data[here] = 1u;
    }
  }
  if (level == 0u) {
    const vec4 v = valid.data[here] != 0u ? pyramid.data[here] : vec4(0.0);
    filled_depth.data[here] = v.w;
    for (uint k = 0u; k < 3u; ++k) filled_normal.data[3u * here + k] = v[k];
  }
}
