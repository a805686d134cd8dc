#version 450
// passthrough: Radiance -> Output with format conversion only. No filtering
// and no sanitizing (values are copied as they come; fp32 -> fp16 rounds to
// nearest even, overflow becomes Inf). One invocation per pixel pair.
//
// Bindings: 0 FrameConstants, 1 radiance (rgb), 2 output (rgb)
// Specialization: 0 workgroup size, 1 radiance is fp16, 2 output is fp16
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"

layout(constant_id = 1) const bool RADIANCE_HALF = false;
layout(constant_id = 2) const bool OUTPUT_HALF = false;

layout(std430, set = 0, binding = 1) readonly buffer RadiancePlane { uint data[]; } radiance;
layout(std430, set = 0, binding = 2) writeonly buffer OutputPlane { uint data[]; } result;

void main() {
  uint pair = dn_invocation_index();
  uint n = frame.size.z;
  uint p0 = 2u * pair;
  if (p0 >= n) return;
  bool has_b = p0 + 1u < n;
  vec3 a = DN_LOAD3(radiance, RADIANCE_HALF, p0);
  vec3 b = vec3(0.0);
  if (has_b) b = DN_LOAD3(radiance, RADIANCE_HALF, p0 + 1u);
  DN_STORE_RGB_PAIR(result, OUTPUT_HALF, pair, a, b, has_b)
}
