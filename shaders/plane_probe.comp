#version 450
// Test kernel for plane.glsl: decodes a plane of 1, 2 or 3 components in fp16
// or fp32 through the DN_LOADn macros and writes every component as fp32.
// Not used by any pipeline.
//
// Bindings: 0 FrameConstants (size.z = pixel count), 1 input plane, 2 output (fp32)
// Specialization: 0 workgroup size, 1 input is fp16, 2 components (1..3)
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"

layout(constant_id = 1) const bool INPUT_HALF = false;
layout(constant_id = 2) const uint COMPONENTS = 1u;

layout(std430, set = 0, binding = 1) readonly buffer InputPlane { uint data[]; } plane;
layout(std430, set = 0, binding = 2) writeonly buffer Decoded { float data[]; } decoded;

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  if (COMPONENTS == 1u) {
    decoded.data[p] = DN_LOAD1(plane, INPUT_HALF, p);
  } else if (COMPONENTS == 2u) {
    vec2 v = DN_LOAD2(plane, INPUT_HALF, p);
    decoded.data[2u * p] = v.x;
    decoded.data[2u * p + 1u] = v.y;
  } else {
    vec3 v = DN_LOAD3(plane, INPUT_HALF, p);
    decoded.data[3u * p] = v.x;
    decoded.data[3u * p + 1u] = v.y;
    decoded.data[3u * p + 2u] = v.z;
  }
}
