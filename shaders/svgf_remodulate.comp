#version 450
// svgf_remodulate: Output = filtered demodulated colour * guarded albedo
// (+ the filtered specular in split mode, + sanitized emission, never
// filtered) in the session's output format (docs/pipelines.md, "svgf in
// detail", 4). One invocation per pixel pair.
//
// Bindings: 0 FrameConstants, 1 illumination (the last a-trous output), 2 albedo,
//   3 emission (bound to albedo and ignored when the session has none), 4 output,
//   5 specular illumination (split mode; bound to binding 1 and ignored otherwise)
// Specialization: 0 workgroup size, 1 albedo is fp16, 2 emission is fp16,
//   3 the session has emission, 4 output is fp16, 5 split mode (add binding 5)
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"

layout(constant_id = 1) const bool ALBEDO_HALF = false;
layout(constant_id = 2) const bool EMISSION_HALF = false;
layout(constant_id = 3) const bool HAS_EMISSION = false;
layout(constant_id = 4) const bool OUTPUT_HALF = false;
layout(constant_id = 5) const bool HAS_SPECULAR = false;

layout(std430, set = 0, binding = 1) readonly buffer Illumination { vec4 data[]; } illum;
layout(std430, set = 0, binding = 2) readonly buffer AlbedoPlane { uint data[]; } albedo;
layout(std430, set = 0, binding = 3) readonly buffer EmissionPlane { uint data[]; } emission;
layout(std430, set = 0, binding = 4) writeonly buffer OutputPlane { uint data[]; } result;
layout(std430, set = 0, binding = 5) readonly buffer Specular { vec4 data[]; } specular;

#include "svgf_guards.glsl"

vec3 remodulate(uint p) {
  vec3 c = illum.data[p].rgb * dn_svgf_albedo(DN_LOAD3(albedo, ALBEDO_HALF, p));
  if (HAS_SPECULAR) c += specular.data[p].rgb;
  if (HAS_EMISSION) c += dn_svgf_sanitize(DN_LOAD3(emission, EMISSION_HALF, p));
  return c;
}

void main() {
  uint pair = dn_invocation_index();
  uint n = frame.size.z;
  uint p0 = 2u * pair;
  if (p0 >= n) return;
  bool has_b = p0 + 1u < n;
  vec3 a = remodulate(p0);
  vec3 b = vec3(0.0);
  if (has_b) b = remodulate(p0 + 1u);
  DN_STORE_RGB_PAIR(result, OUTPUT_HALF, pair, a, b, has_b)
}
