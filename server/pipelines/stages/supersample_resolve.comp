#version 450
// supersample_resolve: a pixel is the mean of its samples' colours, the guide
// (sample 0) its own filtered colour and each extra sample the filtered
// colour of the guide it was assigned to (paper 001 §5); samples that took no
// part are left out. Two pixels per invocation (DN_STORE_RGB_PAIR).
//
// Resources: supersample_resolve.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "pass.glsl"
#include "generated/passes/supersample_resolve.pass"

#include "supersample.glsl"

vec3 resolved(uint p) {
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  vec3 sum = DN_LOAD3(src, p);
  float count = 1.0;
  uint word = assignment_at(p);
  for (uint j = 1u; j <= SAMPLES; ++j) {
    uint code = dn_sample_code(word, j);
    if (code == DN_SAMPLE_UNUSED) continue;
    ivec2 g = pos + dn_sample_guide_offset(code);  // inside: assign picks only pixels inside
    sum += DN_LOAD3(src, uint(g.y) * frame.size.x + uint(g.x));
    count += 1.0;
  }
  return sum / count;
}

void main() {
  uint pair = dn_invocation_index();
  uint p0 = 2u * pair;
  if (p0 >= frame.size.z) return;
  bool has_b = p0 + 1u < frame.size.z;
  vec3 a = resolved(p0);
  vec3 b = has_b ? resolved(p0 + 1u) : vec3(0.0);
  DN_STORE_RGB_PAIR(result, pair, a, b, has_b)
}
