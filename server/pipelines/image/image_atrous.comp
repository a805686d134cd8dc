#version 450
// image_atrous: one a-trous iteration (the 5x5 B3 spline, taps 2^i apart)
// over the demodulated colour, each tap weighed by the guides
// (dn_image_geometry_weight) and by exp(-|l_p - l_q| / (phi_luminance *
// sigma_pq)), sigma_pq the standard deviation of the less noisy of p and q
// as carried in .w: a noise-free bright region (a light seen directly) does
// not spread into its noisy surroundings, nor a firefly into its
// neighbours; the variance is carried as sum w^2 var_q / (sum w)^2 (Schied
// 2017). A pixel without noise (sigma 0) keeps its colour; a tap without
// noise weighs 1 at p's luminance exactly, else 0. One invocation per pixel.
//
// Resources: image_atrous.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "luminance.glsl"
#include "pass.glsl"
#include "generated/passes/image_atrous.pass"
#include "image.glsl"

const float kB3[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

void main() {
  const ivec2 size = ivec2(frame.size.xy);
  const uint pi = dn_invocation_index();
  if (pi >= frame.size.z) return;
  const ivec2 p = ivec2(int(pi % uint(size.x)), int(pi / uint(size.x)));

  const vec4 cp = src_at(pi);
  const vec4 gp = guide_at(pi);
  const vec3 ap = dn_image_albedo(pi);
  const float lp = dn_luminance(cp.rgb);
  const float sigma = sqrt(max(cp.w, 0.0));
  if (!(sigma > 0.0)) {
    dst.data[pi] = vec4(cp.rgb, 0.0);
    return;
  }
  const float phi = DN_PARAM_VALUE(image, phi_luminance);

  const float centre = kB3[0] * kB3[0];
  vec3 colour = centre * cp.rgb;
  float variance = centre * centre * cp.w;
  float weight = centre;
  for (int y = -2; y <= 2; ++y)
    for (int x = -2; x <= 2; ++x) {
      if (x == 0 && y == 0) continue;
      const ivec2 q = p + ivec2(x, y) * STEP;
      if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
      const uint qi = uint(q.y) * uint(size.x) + uint(q.x);
      const vec4 cq = src_at(qi);
      const float w = kB3[abs(x)] * kB3[abs(y)] *
                      dn_image_geometry_weight(gp, guide_at(qi), ap, dn_image_albedo(qi), float(STEP) * length(vec2(x, y))) *
                      exp(-abs(lp - dn_luminance(cq.rgb)) / max(phi * sqrt(max(min(cp.w, cq.w), 0.0)), 1e-30));
      colour += w * cq.rgb;
      variance += w * w * cq.w;
      weight += w;
    }
  dst.data[pi] = vec4(colour / weight, variance / (weight * weight));
}
