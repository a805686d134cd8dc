#version 450
// bench_bilinear_image (bench/bilinear_bench.cpp): the same fetch as
// bench_bilinear_buffer from a sampled image with linear filtering
// (clamp-to-edge), to measure it against the buffer fetch. Not used by any
// pipeline; the sampler (binding 2) is not a storage buffer, so it is
// declared here and not in the pass declaration.
#extension GL_GOOGLE_include_directive : require
#include "grid2d.glsl"
#include "pass.glsl"
#include "generated/passes/bench_bilinear_image.pass"

layout(set = 0, binding = 2) uniform sampler2D source_image;

void main() {
  const uvec2 p = dn_pixel();
  if (!dn_in_grid(p)) return;
  const vec2 pos = vec2(p) + 0.5 + vec2(dn_arg_offset_x(), dn_arg_offset_y());
  result.data[dn_grid_index(p, dn_grid.size)] = textureLod(source_image, pos / vec2(dn_grid.source), 0.0);
}
