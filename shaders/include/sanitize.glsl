// Input sanitizing, applied where a pass first reads a plane so that no bad
// value ever enters history or a product overflows (docs/pipelines.md,
// "Sanitize rule", with the table of guide rules):
//   radiance: NaN, +Inf, -Inf -> 0; negative -> 0 (max(x, 0)); above
//             DN_MAX_RADIANCE -> 0 (a bad sample, like +Inf); per component
//   normal:   any non-finite component, or |n|^2 not finite (a huge normal)
//             -> the zero vector ("no normal": rejects every tap)
//   depth:    a pixel is foreground iff depth is finite and within
//             [DN_DEPTH_MIN, DN_DEPTH_MAX]; else background
//   motion:   (in pixels) any non-finite component or one beyond
//             DN_MOTION_MAX -> no reprojection for that pixel
//   albedo, where a pass demodulates by it: a component outside
//             [1e-3, 1e3] or not finite divides and multiplies by 1
//             (docs/protocol.md §7.7); where it guides a filter (stat's base
//             weight): non-finite -> 0, then clamped to [0, DN_ALBEDO_MAX]
//   roughness: not finite -> 1 (rough: no clipping, no reflection class),
//             else clamped to [0, 1]
//   specular F0: per component, not finite -> 0, else clamped to [0, 1]
//   sample count: a pixel is sampled iff its count is finite and > 0
// Tests are done on the bits so that no compiler fast-math can fold them away.
#ifndef DN_SANITIZE_GLSL
#define DN_SANITIZE_GLSL

bool dn_is_finite(float x) { return (floatBitsToUint(x) & 0x7f800000u) != 0x7f800000u; }
bool dn_is_finite(vec2 v) { return dn_is_finite(v.x) && dn_is_finite(v.y); }
bool dn_is_finite(vec3 v) { return dn_is_finite(v.x) && dn_is_finite(v.y) && dn_is_finite(v.z); }

// Finite radiance above this counts as a bad sample: it keeps squares of the
// demodulated colour (<= 1e15 after the albedo guard: moments, variances,
// Welch statistics) and sums of many of them far from fp32 overflow.
const float DN_MAX_RADIANCE = 1e12;
float dn_sanitize_radiance(float x) { return dn_is_finite(x) && x <= DN_MAX_RADIANCE ? max(x, 0.0) : 0.0; }
// A radiance the sanitizer leaves as it is (finite, 0 to DN_MAX_RADIANCE).
bool dn_is_valid_radiance(vec3 c) {
  return dn_is_finite(c) && all(greaterThanEqual(c, vec3(0.0))) && all(lessThanEqual(c, vec3(DN_MAX_RADIANCE)));
}
vec3 dn_sanitize_radiance(vec3 c) {
  return vec3(dn_sanitize_radiance(c.x), dn_sanitize_radiance(c.y), dn_sanitize_radiance(c.z));
}

// |n|^2 overflows only for a normal far from unit length (protocol: unit normals).
vec3 dn_sanitize_normal(vec3 n) { return dn_is_finite(n) && dn_is_finite(dot(n, n)) ? n : vec3(0.0); }

// Albedo bounds: below the lower one a division amplifies noise without
// limit; above the upper one (no physical albedo reaches it) the product of
// remodulation overflows (3.4e38 x a filtered colour -> Inf).
const float DN_ALBEDO_MIN = 1e-3;
const float DN_ALBEDO_MAX = 1e3;
vec3 dn_sanitize_albedo(vec3 a) {
  return vec3(dn_is_finite(a.x) ? clamp(a.x, 0.0, DN_ALBEDO_MAX) : 0.0,
              dn_is_finite(a.y) ? clamp(a.y, 0.0, DN_ALBEDO_MAX) : 0.0,
              dn_is_finite(a.z) ? clamp(a.z, 0.0, DN_ALBEDO_MAX) : 0.0);
}
float dn_guarded_albedo(float a) {
  return (dn_is_finite(a) && a >= DN_ALBEDO_MIN && a <= DN_ALBEDO_MAX) ? a : 1.0;
}
vec3 dn_guarded_albedo(vec3 a) { return vec3(dn_guarded_albedo(a.x), dn_guarded_albedo(a.y), dn_guarded_albedo(a.z)); }

// A modulator below DN_ALBEDO_MIN in every component (or not finite): no lobe of that kind.
bool dn_no_reflectance(vec3 a) { return !(max(a.r, max(a.g, a.b)) >= DN_ALBEDO_MIN); }
// A pixel whose (diffuse) albedo is not a reflectance, below DN_ALBEDO_MIN
// in every component (a mirror or metal when the albedo is a diffuse colour)
// or above DN_REFLECTANCE_MAX in one (Cycles' Denoising Albedo of a light
// seen in a mirror), or not finite: the guides cannot tell what it shows from
// its neighbours, and what it shows moves with the camera, not with its
// surface, so only a still pixel's history holds the same point.
const float DN_REFLECTANCE_MAX = 1.5;
bool dn_unexplained(vec3 a) { return dn_no_reflectance(a) || !(max(a.r, max(a.g, a.b)) <= DN_REFLECTANCE_MAX); }

// Depth bounds of a foreground pixel: the smallest normal float (a denormal
// depth counts as 0 whether or not the device flushes it) and a distance
// beyond which depth means "infinitely far" (its square stays finite).
const float DN_DEPTH_MIN = 1.17549435e-38;
const float DN_DEPTH_MAX = 1e18;
bool dn_is_foreground(float depth) {
  return dn_is_finite(depth) && depth >= DN_DEPTH_MIN && depth <= DN_DEPTH_MAX;
}

// Motion beyond 2^20 px points off any image; bounding it keeps positions
// and float -> int conversions exact and in range.
const float DN_MOTION_MAX = 1048576.0;
bool dn_motion_usable(vec2 mv_px) {
  return dn_is_finite(mv_px) && abs(mv_px.x) <= DN_MOTION_MAX && abs(mv_px.y) <= DN_MOTION_MAX;
}

float dn_sanitize_unit(float v, float fallback) { return dn_is_finite(v) ? clamp(v, 0.0, 1.0) : fallback; }
float dn_sanitize_roughness(float r) { return dn_sanitize_unit(r, 1.0); }
vec3 dn_sanitize_f0(vec3 f0) {
  return vec3(dn_sanitize_unit(f0.x, 0.0), dn_sanitize_unit(f0.y, 0.0), dn_sanitize_unit(f0.z, 0.0));
}

bool dn_is_sampled(float count) { return dn_is_finite(count) && count > 0.0; }

#endif
