#version 450
// Test kernel for plane.glsl: decodes a plane of 1, 2 or 3 fp32 components
// through the DN_LOADn macros and writes every component.
// Not used by any pipeline.
//
// Resources: plane_probe.pass (binding 0 FrameConstants, size.z = pixel count).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "pass.glsl"
#include "generated/passes/plane_probe.pass"

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  if (COMPONENTS == 1u) {
    decoded.data[p] = DN_LOAD1(plane, p);
  } else if (COMPONENTS == 2u) {
    vec2 v = DN_LOAD2(plane, p);
    decoded.data[2u * p] = v.x;
    decoded.data[2u * p + 1u] = v.y;
  } else {
    vec3 v = DN_LOAD3(plane, p);
    decoded.data[3u * p] = v.x;
    decoded.data[3u * p + 1u] = v.y;
    decoded.data[3u * p + 2u] = v.z;
  }
}
