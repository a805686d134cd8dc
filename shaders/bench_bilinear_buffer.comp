#version 450
// bench_bilinear_buffer (bench/bilinear_bench.cpp): every pixel fetches the
// source buffer bilinearly at its centre + a constant sub-pixel offset
// through bilinear.glsl (every tap valid). Not used by any pipeline.
//
// Push constants (grid2d.glsl): size = source = the grid; args.xy = offset (float bits).
#extension GL_GOOGLE_include_directive : require
#include "grid2d.glsl"
#include "bilinear.glsl"
#include "pass.glsl"
#include "generated/passes/bench_bilinear_buffer.pass"

DN_BILINEAR_FETCH_FN(fetch_source, source, dn_bilinear_any)

void main() {
  const uvec2 p = dn_pixel();
  if (!dn_in_grid(p)) return;
  const vec2 pos = vec2(p) + 0.5 + vec2(dn_arg_offset_x(), dn_arg_offset_y());
  float total;
  result.data[dn_grid_index(p, dn_grid.size)] = fetch_source(pos, dn_grid.source, total);
}
