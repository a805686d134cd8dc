#version 450
// bench_gather_buffer (bench/gather_bench.cpp): every pixel sums the vec4
// values of its 5x5 neighbourhood (clamped to the grid) read from a storage
// buffer, the way the a-trous passes read their taps. Not used by any pipeline.
#extension GL_GOOGLE_include_directive : require
#include "grid2d.glsl"
#include "pass.glsl"
#include "generated/passes/bench_gather_buffer.pass"

void main() {
  const uvec2 p = dn_pixel();
  if (!dn_in_grid(p)) return;
  const ivec2 last = ivec2(dn_grid.size) - 1;
  vec4 sum = vec4(0.0);
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx) {
      ivec2 q = clamp(ivec2(p) + ivec2(dx, dy), ivec2(0), last);
      sum += source.data[dn_grid_index(uvec2(q), dn_grid.size)];
    }
  result.data[dn_grid_index(p, dn_grid.size)] = sum;
}
