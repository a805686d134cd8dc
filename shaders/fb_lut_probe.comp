#version 450
// Test kernel for fb_lut.glsl: evaluates dn_fb_lut at the (cos θ_o, α)
// points of `points` and writes the (A, B) it returns. Not used by any
// pipeline (tests/pipelines/stages/fb_lut_test.cpp).
//
// Resources: binding 0 ProbeConstants (x: point count), then fb_lut_probe.pass.
#extension GL_GOOGLE_include_directive : require
#include "pass.glsl"
#include "generated/passes/fb_lut_probe.pass"
#include "fb_lut.glsl"

layout(local_size_x_id = 0, local_size_y = 1, local_size_z = 1) in;

layout(std140, set = 0, binding = 0) readonly buffer ProbeConstants { uvec4 size; } constants;

void main() {
  uint p = gl_GlobalInvocationID.x;
  if (p >= constants.size.x) return;
  vec2 q = points.data[p];
  results.data[p] = dn_fb_lut(q.x, q.y);
}
