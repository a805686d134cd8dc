#version 450
// svgf_remodulate: Output = filtered demodulated colour * guarded albedo
// (+ the filtered specular in split mode, + sanitized emission, never
// filtered) in the session's output format (docs/pipelines.md, "svgf in
// detail", 4). One invocation per pixel pair.
// With TAA (taa_alpha > 0, spec constant 6) it writes, instead of Output, the
// current colour and the bilinearly reprojected previous final output for
// svgf_taa (docs/pipelines.md, "svgf in detail", 5): the TAA history is read
// only here and rewritten only by svgf_taa, so one persistent copy suffices.
//
// Bindings: 0 FrameConstants, 1 illumination (the last a-trous output), 2 albedo,
//   3 emission (bound to albedo and ignored when the session has none), 4 output,
//   5 specular illumination (split mode; bound to binding 1 and ignored otherwise),
//   6 depth, 7 motion, 8 TAA history (previous final output, 3 fp32 per pixel),
//   9 TAA current: vec4(current rgb, 1 if the history is usable here else 0),
//   10 TAA previous: vec4(reprojected previous final output, 0)
//   (6..10 are bound to stand-ins and ignored without TAA),
//   11 specular factor (svgf-fb: F_beta, 3 fp32 per pixel, guarded like
//   albedo; bound to albedo and ignored otherwise)
// Specialization: 0 workgroup size, 1 albedo is fp16, 2 emission is fp16,
//   3 the session has emission, 4 output is fp16, 5 split mode (add binding 5),
//   6 TAA (write bindings 9 and 10 instead of Output), 7 depth is fp16, 8 motion is fp16,
//   9 multiply the specular illumination by binding 11 (svgf-fb)
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "reproject.glsl"

layout(constant_id = 1) const bool ALBEDO_HALF = false;
layout(constant_id = 2) const bool EMISSION_HALF = false;
layout(constant_id = 3) const bool HAS_EMISSION = false;
layout(constant_id = 4) const bool OUTPUT_HALF = false;
layout(constant_id = 5) const bool HAS_SPECULAR = false;
layout(constant_id = 6) const bool TAA = false;
layout(constant_id = 7) const bool DEPTH_HALF = false;
layout(constant_id = 8) const bool MOTION_HALF = false;
layout(constant_id = 9) const bool SPECULAR_FACTOR = false;

layout(std430, set = 0, binding = 1) readonly buffer Illumination { vec4 data[]; } illum;
layout(std430, set = 0, binding = 2) readonly buffer AlbedoPlane { uint data[]; } albedo;
layout(std430, set = 0, binding = 3) readonly buffer EmissionPlane { uint data[]; } emission;
layout(std430, set = 0, binding = 4) writeonly buffer OutputPlane { uint data[]; } result;
layout(std430, set = 0, binding = 5) readonly buffer Specular { vec4 data[]; } specular;
layout(std430, set = 0, binding = 6) readonly buffer DepthPlane { uint data[]; } depth;
layout(std430, set = 0, binding = 7) readonly buffer MotionPlane { uint data[]; } motion;
layout(std430, set = 0, binding = 8) readonly buffer TaaHistory { float data[]; } taa_history;
layout(std430, set = 0, binding = 9) writeonly buffer TaaCurrent { vec4 data[]; } taa_current;
layout(std430, set = 0, binding = 10) writeonly buffer TaaPrevious { vec4 data[]; } taa_previous;
layout(std430, set = 0, binding = 11) readonly buffer SpecularFactor { uint data[]; } specular_factor;

#include "svgf_guards.glsl"

vec3 remodulate(uint p) {
  vec3 c = illum.data[p].rgb * dn_svgf_albedo(DN_LOAD3(albedo, ALBEDO_HALF, p));
  if (HAS_SPECULAR)
    c += specular.data[p].rgb * (SPECULAR_FACTOR ? dn_svgf_albedo(DN_LOAD3(specular_factor, false, p)) : vec3(1.0));
  if (HAS_EMISSION) c += dn_svgf_sanitize(DN_LOAD3(emission, EMISSION_HALF, p));
  return c;
}

vec3 taa_history_at(ivec2 q) {
  uint i = 3u * (uint(q.y) * frame.size.x + uint(q.x));
  return vec3(taa_history.data[i], taa_history.data[i + 1u], taa_history.data[i + 2u]);
}

// TAA: the previous final output at p + mv, bilinear over the taps inside the
// image (renormalized); none when reset, background, motion not finite or the
// accepted weight < DN_MIN_TAP_WEIGHT (off-screen).
void taa_prepare(uint p, vec3 c) {
  uvec2 size = frame.size.xy;
  vec3 prev = vec3(0.0);
  bool valid = false;
  vec2 mv = DN_LOAD2(motion, MOTION_HALF, p) * frame.motion.xy;
  ivec2 origin;
  vec4 weights;
  if ((frame.size.w & DN_FLAG_RESET) == 0u && dn_is_foreground(DN_LOAD1(depth, DEPTH_HALF, p)) && dn_is_finite(mv) &&
      dn_bilinear_footprint(dn_previous_position(p, size.x, mv), size, origin, weights)) {
    vec3 s = vec3(0.0);
    float sw = 0.0;
    ivec2 taps[4] = ivec2[4](origin, origin + ivec2(1, 0), origin + ivec2(0, 1), origin + ivec2(1, 1));
    for (int k = 0; k < 4; ++k) {
      if (!dn_inside(taps[k], size)) continue;
      s += weights[k] * taa_history_at(taps[k]);
      sw += weights[k];
    }
    if (sw >= DN_MIN_TAP_WEIGHT) {
      valid = true;
      prev = s / sw;
    }
  }
  taa_current.data[p] = vec4(c, valid ? 1.0 : 0.0);
  taa_previous.data[p] = vec4(prev, 0.0);
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
  if (TAA) {
    taa_prepare(p0, a);
    if (has_b) taa_prepare(p0 + 1u, b);
    return;
  }
  DN_STORE_RGB_PAIR(result, OUTPUT_HALF, pair, a, b, has_b)
}
