#version 450
// reflect_prepare (reflect, after svgf_fb_factor): classes each pixel by its
// sanitized roughness (reflect.mirror_roughness, reflect.glossy_roughness;
// a non-finite roughness counts as 1, sanitize.glsl; a
// background pixel: none) and writes
//  - the search features of this frame (reflect.glsl): a mirror whose chain
//    hit is not finite, or a glossy pixel without a finite position or unit
//    direction, falls to class none (primary motion);
//  - the specular modulator: F_beta, times the reflected albedo at a mirror
//    (components below the albedo guard, or not finite, count as 1: a mirror
//    that shows the sky is demodulated by F_beta alone);
//  - the specular chain's depth and normal: at a mirror whose chain hit is
//    foreground, the virtual depth and the reflected surface's normal (its
//    edges are the reflection's, paper 001 §4.1), else the primary ones;
//  - with VIRTUAL_START, the virtual point's motion (reflect_motion's third
//    start): the camera ray extended by the reflection's length, at a mirror
//    X = C + (position - C) * reflection_depth / depth (the virtual depth
//    unfolds the whole chain), at a glossy pixel position + the unit view
//    direction * reflection_distance; projected with the previous frame's
//    view-projection, minus the pixel centre (1e30 where any of it is
//    missing or the point is behind the previous camera). C is the camera
//    centre, inverse_view_projection * (0, 0, 1, 0) dehomogenised (the point
//    every perspective projection sends to w = 0);
//  - with FOOTPRINT, the spatial bandwidth of Eq. 6 (svgf_atrous's
//    SPATIAL_BANDWIDTH): at a glossy pixel with a finite footprint f >= 0,
//    sigma = max(exp(-f / footprint_omega), DN_REFLECT_MIN_BANDWIDTH) in
//    a-trous steps; 0 (no spatial term) elsewhere.
// docs/pipelines.md, "reflect".
//
// Resources: reflect_prepare.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "pass.glsl"
#include "generated/passes/reflect_prepare.pass"

#include "svgf_guards.glsl"
#include "reflect.glsl"

// Eq. 6's floor: a huge footprint must not leave a kernel of p alone.
const float DN_REFLECT_MIN_BANDWIDTH = 0.05;

// The motion in pixels, to the previous frame, of world point x seen at
// pixel p; DN_REFLECT_INVALID when x is behind the previous camera.
vec2 motion_of(vec3 x, uint p) {
  vec4 clip = frame.previous_view_projection * vec4(x, 1.0);
  if (!(clip.w > 0.0)) return vec2(DN_REFLECT_INVALID);
  vec2 ndc = clip.xy / clip.w;
  vec2 prev = vec2((ndc.x * 0.5 + 0.5) * float(frame.size.x), (0.5 - ndc.y * 0.5) * float(frame.size.y));
  vec2 mv = prev - (vec2(float(p % frame.size.x), float(p / frame.size.x)) + 0.5);
  return dn_is_finite(mv) ? mv : vec2(DN_REFLECT_INVALID);
}

// The camera centre (see above).
vec3 camera_centre() {
  vec4 h = frame.inverse_view_projection * vec4(0.0, 0.0, 1.0, 0.0);
  return h.xyz / h.w;
}

// The virtual point's motion at a mirror: the camera ray through the primary
// hit o unfolded by the chain, virtual depth vz over primary depth z.
vec2 mirror_virtual_motion(uint p, vec3 o, float vz, float z) {
  vec3 c = camera_centre();
  if (!dn_is_finite(c) || !dn_is_finite(o) || !dn_is_foreground(vz)) return vec2(DN_REFLECT_INVALID);
  return motion_of(c + (o - c) * (vz / z), p);
}

// At a glossy pixel: that ray extended past o by the representative ray's hit distance t.
vec2 glossy_virtual_motion(uint p, vec3 o, float t) {
  vec3 c = camera_centre();
  float len = length(o - c);
  if (!dn_is_finite(c) || !dn_reflect_ray_exists(t) || !(len > 0.0)) return vec2(DN_REFLECT_INVALID);
  return motion_of(o + (o - c) * (t / len), p);
}

float reflection_class(uint p, float z) {
  float r = dn_sanitize_roughness(DN_LOAD1(roughness, p));
  if (!dn_is_foreground(z)) return DN_REFLECT_NONE;
  if (r < DN_PARAM_VALUE(reflect, mirror_roughness)) return DN_REFLECT_MIRROR;
  if (r < DN_PARAM_VALUE(reflect, glossy_roughness)) return DN_REFLECT_GLOSSY;
  return DN_REFLECT_NONE;
}

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  float z = DN_LOAD1(depth, p);
  const float primary_depth = z;
  vec3 n = DN_LOAD3(normal, p);
  float cls = reflection_class(p, z);
  vec3 f = vec3(fb_factor.data[3u * p], fb_factor.data[3u * p + 1u], fb_factor.data[3u * p + 2u]);

  vec4 a = vec4(0.0), b = vec4(0.0);
  vec2 vmv = vec2(DN_REFLECT_INVALID);  // VIRTUAL_START
  if (cls == DN_REFLECT_MIRROR) {
    vec3 w = DN_LOAD3(reflection_position, p);
    if (dn_is_finite(w)) {
      a = vec4(w, cls);
      f *= dn_guarded_albedo(DN_LOAD3(reflection_albedo, p));
      float vz = DN_LOAD1(reflection_depth, p);
      if (VIRTUAL_START) vmv = mirror_virtual_motion(p, DN_LOAD3(position, p), vz, primary_depth);
      if (dn_is_foreground(vz)) {
        z = vz;
        n = DN_LOAD3(reflection_normal, p);
      }
    } else {
      cls = DN_REFLECT_NONE;
    }
  } else if (cls == DN_REFLECT_GLOSSY) {
    vec3 o = DN_LOAD3(position, p);
    vec3 d = DN_LOAD3(reflection_direction, p);
    float t = DN_LOAD1(reflection_distance, p);
    float len = length(d);
    if (dn_is_finite(o) && dn_is_finite(len) && len > 0.5) {
      a = vec4(o, cls);
      b = vec4(d / len, dn_reflect_ray_exists(t) ? t : 0.0);
      if (VIRTUAL_START) vmv = glossy_virtual_motion(p, o, t);
    } else {
      cls = DN_REFLECT_NONE;
    }
  }
  if (VIRTUAL_START) virtual_motion.data[p] = vmv;
  if (FOOTPRINT) {
    float fp = DN_LOAD1(reflection_footprint, p);
    bool take = cls == DN_REFLECT_GLOSSY && dn_is_finite(fp) && fp >= 0.0;
    float omega = DN_PARAM_VALUE(reflect, footprint_omega);
    bandwidth.data[p] = take ? max(exp(-fp / omega), DN_REFLECT_MIN_BANDWIDTH) : 0.0;
  }
  features.data[2u * p] = a;
  features.data[2u * p + 1u] = b;
  modulator.data[3u * p] = f.x;
  modulator.data[3u * p + 1u] = f.y;
  modulator.data[3u * p + 2u] = f.z;
  feature_depth.data[p] = z;
  feature_normal.data[3u * p] = n.x;
  feature_normal.data[3u * p + 1u] = n.y;
  feature_normal.data[3u * p + 2u] = n.z;
}
