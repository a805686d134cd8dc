// What image's passes share: the guarded albedo and the geometric weight of a
// tap, each guide counted only where the session has its plane (HAS_*).
#ifndef DN_IMAGE_GLSL
#define DN_IMAGE_GLSL

#include "sanitize.glsl"

// The albedo a pixel's colour is divided by before filtering and multiplied
// by after; 1 without an albedo plane or where the guard refuses it.
vec3 dn_image_albedo(uint p) {
  if (!HAS_ALBEDO) return vec3(1.0);
  return dn_guarded_albedo(DN_LOAD3(albedo, p));
}

// Tap q's weight for pixel p from the guides alone: its normal, depth and
// albedo against p's, `dist` pixels away. A background pixel (depth) takes
// only background taps; a pixel without a usable normal (the zero vector)
// takes none but itself.
float dn_image_geometry_weight(vec4 gp, vec4 gq, vec3 ap, vec3 aq, float dist) {
  float w = 1.0;
  if (HAS_NORMAL) w *= pow(max(0.0, dot(gp.xyz, gq.xyz)), DN_PARAM_VALUE(image, phi_normal));
  if (HAS_DEPTH) {
    const bool fp = dn_is_foreground(gp.w), fq = dn_is_foreground(gq.w);
    if (fp != fq) return 0.0;
    if (fp) w *= exp(-abs(gp.w - gq.w) / (DN_PARAM_VALUE(image, phi_depth) * dist * gp.w));
  }
  if (HAS_ALBEDO) w *= exp(-dot(abs(ap - aq), vec3(1.0)) / DN_PARAM_VALUE(image, phi_albedo));
  return w;
}

// Pixel index of p + d, clamped to the frame.
uint dn_image_clamped(ivec2 p, ivec2 d, ivec2 size) {
  const ivec2 q = clamp(p + d, ivec2(0), size - 1);
  return uint(q.y) * uint(size.x) + uint(q.x);
}

#endif
