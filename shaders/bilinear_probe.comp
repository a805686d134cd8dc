#version 450
// Test kernel for bilinear.glsl (tests/gpu/bilinear_test.cpp): the fetch of
// a vec4 buffer at one position per invocation, taps masked by a validity
// buffer. Not used by any pipeline.
//
// Push constants (grid2d.glsl): size = the grid of positions, source = the
// grid of the buffer fetched.
#extension GL_GOOGLE_include_directive : require
#include "grid2d.glsl"
#include "bilinear.glsl"
#include "pass.glsl"
#include "generated/passes/bilinear_probe.pass"

bool tap_valid(uint i) { return valid.data[i] != 0u; }
DN_BILINEAR_FETCH_FN(fetch_source, source, tap_valid)

void main() {
  const uvec2 p = dn_pixel();
  if (!dn_in_grid(p)) return;
  const uint i = dn_grid_index(p, dn_grid.size);
  float total;
  result.data[i] = fetch_source(positions.data[i], dn_grid.source, total);
  weight.data[i] = total;
}
