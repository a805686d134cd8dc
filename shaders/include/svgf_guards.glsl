// svgf guards and constants (docs/pipelines.md, "svgf in detail"):
// epsilons, the history normal packing. Needs sanitize.glsl.
#ifndef DN_SVGF_GUARDS_GLSL
#define DN_SVGF_GUARDS_GLSL

#include "reproject.glsl"

// Added to the filtered variance under the square root of the luminance
// edge-stopping function (Falcor adds 1e-10, which breaks scale equivariance
// near k = 1e-3); it matters only for luminance std devs below about 1e-10.
const float DN_SVGF_VARIANCE_EPS = 1e-20;
// Relative luminance guard of the 7x7 variance estimate (see svgf_variance.comp).
const float DN_SVGF_LUMINANCE_EPS = 1e-20;

// The illumination variance (.w) of a pixel with no data (MASKED chains:
// never sampled, nothing reprojected): it takes no part in any neighbour's
// filter, and a-trous keeps it unless a neighbour has data (svgf_atrous.comp).
const float DN_SVGF_NO_DATA = -1.0;

// The floor of a chain's temporal blend weight: svgf's alpha_colour, or
// alpha_specular (group specular) on reflect's specular chain (SPECULAR_ALPHA, a
// specialization constant of svgf_reproject and svgf_variance).
#define DN_SVGF_ALPHA_OF(is_specular) ((is_specular) ? DN_PARAM_VALUE(specular, alpha_specular) : DN_PARAM_VALUE(svgf, alpha_colour))
#define DN_SVGF_ALPHA_COLOUR DN_SVGF_ALPHA_OF(SPECULAR_ALPHA)

// What a sample's luminance variance is divided by to steer the a-trous
// edge-stopping (variance_of_mean): the samples the temporal colour
// averages, its first 1/alpha frames a true mean of `len` samples, after that
// an exponential average whose variance is alpha / (2 - alpha) of a
// sample's. Where svgf_reproject handed the filter a still pixel's running
// mean of still_n samples (more than DN_STILL_FILTER_FROM; 0: none),
// still_n sqrt(still_n / DN_STILL_FILTER_FROM): the edge-stopping narrows
// faster than the mean's noise falls, so the blur the filter leaves at an
// edge falls faster than that noise too (with still_n alone it stayed
// about as large: dnrender scene 4 above the plain mean by HDR-FLIP after
// 64 frames). 1 when off.
float dn_svgf_variance_divisor(float len, float still_n, bool specular_alpha) {
  if (DN_PARAM_VALUE(svgf, variance_of_mean) == 0.0) return 1.0;
  if (still_n > DN_STILL_FILTER_FROM) return still_n * sqrt(still_n / DN_STILL_FILTER_FROM);
  float a = DN_SVGF_ALPHA_OF(specular_alpha);
  return a > 0.0 ? clamp(len, 1.0, (2.0 - a) / a) : max(len, 1.0);
}
// HDR step rule of the a-trous variance prefilter: a neighbour's variance
// counts for p only when |l_p - l_q| <= DN_SVGF_STEP_SIGMAS * sqrt(v_q), so a
// bright pixel's variance does not open a dark neighbour's luminance
// edge-stopping to it (docs/pipelines.md, "svgf in detail").
const float DN_SVGF_STEP_SIGMAS = 3.0;

// Octahedral unit-normal packing into two snorm16 (history only).
uint dn_svgf_pack_normal(vec3 n) {
  vec3 a = abs(n);
  n /= (a.x + a.y + a.z);
  vec2 e = n.xy;
  if (n.z < 0.0) e = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  return packSnorm2x16(e);
}
vec3 dn_svgf_unpack_normal(uint bits) {
  vec2 e = unpackSnorm2x16(bits);
  vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
  if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  return normalize(n);
}

#endif
