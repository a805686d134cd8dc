#version 450
// image_prepare: per pixel, the sanitized radiance divided by its guarded
// albedo (with an albedo plane), and in .w its luminance's residual r
// against the mean of its 4 neighbours (clamped at the frame's edge): noise
// and the signal's curvature, which image_noise tells apart over the
// pixel's surface. Each pixel whose 5-pixel mean m is above 0
// counts t = r^2 / (1.25 m^2) in the gain histogram (image_gain.glsl). The
// guide: the sanitized normal (zero if none) and depth (0 if none). One
// invocation per pixel.
//
// Resources: image_prepare.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "luminance.glsl"
#include "pass.glsl"
#include "generated/passes/image_prepare.pass"
#include "image.glsl"
#include "image_gain.glsl"

vec3 demodulated(uint p) { return dn_sanitize_radiance(DN_LOAD3(radiance, p)) / dn_image_albedo(p); }

void main() {
  const ivec2 size = ivec2(frame.size.xy);
  const uint pi = dn_invocation_index();
  if (pi >= frame.size.z) return;
  const ivec2 p = ivec2(int(pi % uint(size.x)), int(pi / uint(size.x)));

  const vec3 c = demodulated(pi);
  float around = 0.0;
  const ivec2 dirs[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
  for (int k = 0; k < 4; ++k) around += dn_luminance(demodulated(dn_image_clamped(p, dirs[k], size)));
  const float l = dn_luminance(c);
  const float r = l - 0.25 * around;
  signal.data[pi] = vec4(c, r);
  const float m = 0.2 * (l + around);
  const float t = r * r / (1.25 * m * m);
  if (m > 0.0 && t > 0.0 && dn_is_finite(t)) atomicAdd(histogram.data[dn_gain_bin(t)], 1u);

  const vec3 n = HAS_NORMAL ? dn_sanitize_normal(DN_LOAD3(normal, pi)) : vec3(0.0);
  const float z = HAS_DEPTH ? DN_LOAD1(depth, pi) : 0.0;
  guide.data[pi] = vec4(n, dn_is_foreground(z) ? z : 0.0);
}
