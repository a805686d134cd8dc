#version 450
// svgf_reproject: sanitize, demodulate, luminance moments and temporal
// integration of colour and moments (docs/pipelines.md, "svgf in detail", 1).
// One invocation per pixel.
//
// Bindings: 0 FrameConstants, 1 radiance, 2 albedo, 3 normal, 4 depth, 5 motion,
//   6 colour history, 7 aux history (single copies: read here, rewritten by
//   svgf_variance and the feedback a-trous iteration after this pass),
//   8 illumination (scratch), 9 guide (scratch), 10 temporal (scratch),
//   11 emission (bound to albedo and ignored unless spec constant 8)
// Colour history: vec4(demodulated rgb, length), fp32. Aux history: uvec4(m1, m2,
//   depth (0 = no history here) as fp32 bits, octahedral snorm16x2 normal).
// Illumination: vec4(temporal demodulated rgb, 0) (the variance pass fills .w).
// Guide (read by every later pass instead of the depth and normal planes):
//   uvec4(gz, octahedral snorm16x2 normal, depth gradient dz, 0) with gz = depth
//   for a foreground pixel with a normal, -depth for one without (it takes no
//   neighbour and no pixel takes it), 0 for background.
// Temporal: vec4(m1, m2, length, luminance of the temporal colour).
// Specialization: 0 workgroup size, 1..5 radiance/albedo/normal/depth/motion are fp16,
//   6 demodulate by albedo (false: the specular chain of split mode, albedo = 1),
//   7 write the guide (false: a later chain of split mode, which reads the one
//   the first chain wrote; binding 1 is then its signal: diffuse or specular),
//   8 subtract emission (binding 11) from the signal: radiance mode with an
//   emission channel (radiance includes what the primary hit emits, which
//   svgf_remodulate adds back unfiltered), 9 emission is fp16
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "reproject.glsl"
#include "luminance.glsl"

layout(constant_id = 1) const bool RADIANCE_HALF = false;
layout(constant_id = 2) const bool ALBEDO_HALF = false;
layout(constant_id = 3) const bool NORMAL_HALF = false;
layout(constant_id = 4) const bool DEPTH_HALF = false;
layout(constant_id = 5) const bool MOTION_HALF = false;
layout(constant_id = 6) const bool DEMODULATE = true;
layout(constant_id = 7) const bool WRITE_GUIDE = true;
layout(constant_id = 8) const bool SUBTRACT_EMISSION = false;
layout(constant_id = 9) const bool EMISSION_HALF = false;

layout(std430, set = 0, binding = 1) readonly buffer RadiancePlane { uint data[]; } radiance;
layout(std430, set = 0, binding = 2) readonly buffer AlbedoPlane { uint data[]; } albedo;
layout(std430, set = 0, binding = 3) readonly buffer NormalPlane { uint data[]; } normal;
layout(std430, set = 0, binding = 4) readonly buffer DepthPlane { uint data[]; } depth;
layout(std430, set = 0, binding = 5) readonly buffer MotionPlane { uint data[]; } motion;
layout(std430, set = 0, binding = 6) readonly buffer PrevColour { vec4 data[]; } prev_colour;
layout(std430, set = 0, binding = 7) readonly buffer PrevAux { uvec4 data[]; } prev_aux;
layout(std430, set = 0, binding = 8) writeonly buffer Illumination { vec4 data[]; } illum;
layout(std430, set = 0, binding = 9) writeonly buffer Guide { uvec4 data[]; } guide;
layout(std430, set = 0, binding = 10) writeonly buffer Temporal { vec4 data[]; } temporal;
layout(std430, set = 0, binding = 11) readonly buffer EmissionPlane { uint data[]; } emission;

#include "svgf.glsl"

// Falcor's consistency test of a previous pixel q (the previous pixel must
// have left history: stored depth > 0).
bool tap_valid(ivec2 q, float z, vec3 n, vec2 grad, out vec4 aux) {
  aux = vec4(0.0);
  if (!dn_inside(q, frame.size.xy)) return false;
  uvec4 bits = prev_aux.data[uint(q.y) * frame.size.x + uint(q.x)];
  aux = vec4(uintBitsToFloat(bits.xyz), 0.0);
  if (!(aux.z > 0.0)) return false;
  if (abs(z - aux.z) / (grad.x + 0.01) > 10.0) return false;
  if (distance(n, dn_svgf_unpack_normal(bits.w)) / (grad.y + 0.01) > 16.0) return false;
  return true;
}

void add_tap(ivec2 q, float w, float z, vec3 n, vec2 grad, inout vec3 sc, inout vec2 sm, inout float sl,
             inout float sw) {
  vec4 aux;
  if (!tap_valid(q, z, n, grad, aux)) return;
  vec4 h = prev_colour.data[uint(q.y) * frame.size.x + uint(q.x)];
  sc += w * h.rgb;
  sl += w * h.a;
  sm += w * aux.xy;
  sw += w;
}

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  uvec2 size = frame.size.xy;
  ivec2 pos = ivec2(p % size.x, p / size.x);

  vec3 c = dn_svgf_sanitize(DN_LOAD3(radiance, RADIANCE_HALF, p));
  if (SUBTRACT_EMISSION) c = max(c - dn_svgf_sanitize(DN_LOAD3(emission, EMISSION_HALF, p)), vec3(0.0));
  vec3 a = DEMODULATE ? dn_svgf_albedo(DN_LOAD3(albedo, ALBEDO_HALF, p)) : vec3(1.0);
  vec3 d = c / a;
  float l = dn_luminance(d);
  vec2 m = vec2(l, l * l);
  float z = dn_svgf_depth(p);
  if (!dn_is_foreground(z)) {
    illum.data[p] = vec4(d, 0.0);
    if (WRITE_GUIDE) guide.data[p] = uvec4(0u);
    temporal.data[p] = vec4(m, 0.0, l);
    return;
  }
  vec3 n = dn_svgf_normal(p);
  bool has_normal = dot(n, n) > 0.0;
  vec2 grad = dn_svgf_gradients(pos, z, n);
  vec2 mv = DN_LOAD2(motion, MOTION_HALF, p) * frame.motion.xy;

  vec3 prev = vec3(0.0);
  vec2 prev_m = vec2(0.0);
  float prev_len = 0.0;
  bool valid = false;
  ivec2 origin;
  vec4 weights;
  if ((frame.size.w & DN_FLAG_RESET) == 0u && has_normal && dn_is_finite(mv) &&
      dn_bilinear_footprint(dn_previous_position(p, size.x, mv), size, origin, weights)) {
    vec3 sc = vec3(0.0);
    vec2 sm = vec2(0.0);
    float sl = 0.0, sw = 0.0;
    add_tap(origin, weights.x, z, n, grad, sc, sm, sl, sw);
    add_tap(origin + ivec2(1, 0), weights.y, z, n, grad, sc, sm, sl, sw);
    add_tap(origin + ivec2(0, 1), weights.z, z, n, grad, sc, sm, sl, sw);
    add_tap(origin + ivec2(1, 1), weights.w, z, n, grad, sc, sm, sl, sw);
    if (sw < DN_MIN_TAP_WEIGHT) {
      // Falcor's fallback: equal weights over the valid taps of the 3x3 box
      // around the pixel that contains p_prev.
      sc = vec3(0.0);
      sm = vec2(0.0);
      sl = 0.0;
      sw = 0.0;
      ivec2 centre = ivec2(floor(dn_previous_position(p, size.x, mv)));
      for (int yy = -1; yy <= 1; ++yy)
        for (int xx = -1; xx <= 1; ++xx) add_tap(centre + ivec2(xx, yy), 1.0, z, n, grad, sc, sm, sl, sw);
    }
    if (sw > 0.0) {
      valid = true;
      prev = sc / sw;
      prev_m = sm / sw;
      prev_len = floor(sl / sw + 0.5);  // integral lengths: no fp32 vs exact flips of the len < 4 test
    }
  }
  float len = valid ? min(prev_len + 1.0, DN_PARAM_VALUE(DN_P_svgf_max_history)) : 1.0;
  float alpha = valid ? max(1.0 / len, DN_PARAM_VALUE(DN_P_svgf_alpha_colour)) : 1.0;
  float alpha_m = valid ? max(1.0 / len, DN_PARAM_VALUE(DN_P_svgf_alpha_moments)) : 1.0;
  vec3 colour = mix(prev, d, alpha);
  vec2 moments = mix(prev_m, m, alpha_m);
  illum.data[p] = vec4(colour, 0.0);
  if (WRITE_GUIDE)
    guide.data[p] = uvec4(floatBitsToUint(has_normal ? z : -z), has_normal ? dn_svgf_pack_normal(n) : 0u,
                          floatBitsToUint(grad.x), 0u);
  temporal.data[p] = vec4(moments, len, dn_luminance(colour));
}
