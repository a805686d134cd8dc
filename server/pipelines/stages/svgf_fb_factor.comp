#version 450
// svgf_fb_factor (svgf-fb, first pass): the specular demodulation factor of
// each pixel, F_beta = F0 * A + B with (A, B) the pre-integrated GGX table
// (paper 000 Eq. 7/8, fb_lut.glsl) looked up bilinearly at the pixel's
// (cos theta_o, alpha) (docs/pipelines.md, "svgf-fb").
// cos theta_o = dot(n, -view ray) with the ray through the pixel centre from
// FrameConstants.inverse_view_projection (unjittered: a sub-pixel shift
// changes cos theta_o by far less than the table's resolution). Sanitized
// inputs (sanitize.glsl): a non-finite F0 component counts as 0, a non-finite
// roughness as 1, both clamped to [0, 1]; no normal, or a back-facing one,
// reads cos theta_o = 0. Background pixels get 1 (nothing to demodulate).
// The factor is guarded like albedo (svgf_guards.glsl) where it is used.
//
// Resources: svgf_fb_factor.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "pass.glsl"
#include "generated/passes/svgf_fb_factor.pass"

#include "fb_lut.glsl"

// Unit direction from the camera through the centre of pixel p (world space).
vec3 view_ray(uint p) {
  vec2 size = vec2(frame.size.xy);
  vec2 pixel = vec2(float(p % frame.size.x), float(p / frame.size.x)) + 0.5;
  vec2 ndc = vec2(2.0 * pixel.x / size.x - 1.0, 1.0 - 2.0 * pixel.y / size.y);  // pixel rows go down
  vec4 near = frame.inverse_view_projection * vec4(ndc, -1.0, 1.0);
  vec4 far = frame.inverse_view_projection * vec4(ndc, 1.0, 1.0);
  vec3 d = far.xyz / far.w - near.xyz / near.w;
  float len = length(d);
  return (dn_is_finite(len) && len > 0.0) ? d / len : vec3(0.0, 0.0, -1.0);
}

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  vec3 f = vec3(1.0);
  if (dn_is_foreground(DN_LOAD1(depth, p))) {
    vec3 n = dn_sanitize_normal(DN_LOAD3(normal, p));
    float n2 = dot(n, n);
    float cos_o = n2 > 0.0 ? clamp(-dot(n, view_ray(p)) * inversesqrt(n2), 0.0, 1.0) : 0.0;
    float alpha = dn_sanitize_roughness(DN_LOAD1(roughness, p));
    vec3 f0 = dn_sanitize_f0(DN_LOAD3(specular_f0, p));
    vec2 ab = dn_fb_lut(cos_o, alpha);
    f = f0 * ab.x + ab.y;
  }
  factor.data[3u * p] = f.x;
  factor.data[3u * p + 1u] = f.y;
  factor.data[3u * p + 2u] = f.z;
}
