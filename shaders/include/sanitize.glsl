// Input sanitizing, applied by the first pass of a filtering pipeline so that
// no bad value ever enters history (docs/pipelines.md, "Sanitize rule"):
//   radiance: NaN, +Inf, -Inf -> 0; negative -> 0 (max(x, 0)); per component
//   normal:   any non-finite component -> the zero vector (rejects every tap)
//   depth:    a pixel is foreground iff depth is finite and > 0
//   motion:   any non-finite component -> no reprojection for that pixel
//   albedo, where a pass demodulates by it: a component below 1e-3 or not
//             finite divides and multiplies by 1 (docs/protocol.md §7.7);
//             where it guides a filter (stat's base weight): a non-finite
//             component -> 0
// Tests are done on the bits so that no compiler fast-math can fold them away.
#ifndef DN_SANITIZE_GLSL
#define DN_SANITIZE_GLSL

bool dn_is_finite(float x) { return (floatBitsToUint(x) & 0x7f800000u) != 0x7f800000u; }
bool dn_is_finite(vec2 v) { return dn_is_finite(v.x) && dn_is_finite(v.y); }
bool dn_is_finite(vec3 v) { return dn_is_finite(v.x) && dn_is_finite(v.y) && dn_is_finite(v.z); }

float dn_sanitize_radiance(float x) { return dn_is_finite(x) ? max(x, 0.0) : 0.0; }
vec3 dn_sanitize_radiance(vec3 c) {
  return vec3(dn_sanitize_radiance(c.x), dn_sanitize_radiance(c.y), dn_sanitize_radiance(c.z));
}

vec3 dn_sanitize_normal(vec3 n) { return dn_is_finite(n) ? n : vec3(0.0); }

vec3 dn_sanitize_albedo(vec3 a) {
  return vec3(dn_is_finite(a.x) ? a.x : 0.0, dn_is_finite(a.y) ? a.y : 0.0, dn_is_finite(a.z) ? a.z : 0.0);
}

const float DN_ALBEDO_MIN = 1e-3;
float dn_guarded_albedo(float a) { return (dn_is_finite(a) && a >= DN_ALBEDO_MIN) ? a : 1.0; }
vec3 dn_guarded_albedo(vec3 a) { return vec3(dn_guarded_albedo(a.x), dn_guarded_albedo(a.y), dn_guarded_albedo(a.z)); }

bool dn_is_foreground(float depth) { return dn_is_finite(depth) && depth > 0.0; }

#endif
