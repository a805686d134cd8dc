#version 450
// bench_copy: the copy floor of bench/pipeline_bench. Copies `words` 32-bit
// words from src to dst in a grid-stride loop: one read and one
// write per word, neighbouring invocations on neighbouring words. Not used by
// any pipeline; it measures how fast the device moves bytes through a plain
// compute pass, the bound a memory-bound filter can approach.
//
// Resources: binding 0 CopyConstants (x: words), then bench_copy.pass.
#extension GL_GOOGLE_include_directive : require
#include "pass.glsl"

layout(local_size_x_id = 0, local_size_y = 1, local_size_z = 1) in;

layout(std140, set = 0, binding = 0) readonly buffer CopyConstants { uvec4 size; } constants;
#include "generated/passes/bench_copy.pass"

void main() {
  const uint words = constants.size.x;
  const uint invocations = gl_NumWorkGroups.x * gl_NumWorkGroups.y * gl_WorkGroupSize.x;
  const uint t = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
  for (uint w = t; w < words; w += invocations) dst.data[w] = src.data[w];
}
