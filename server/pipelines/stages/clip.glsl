// History clipping and rejection for highlights and reflections (paper 001
// §4.2.3; Karis 2014; docs/pipelines.md "svgf in detail").
// Neighbourhood clipping of a history colour:
// move h toward the centre of the box [lo, hi] until it lies inside, along
// the line to the centre (clip, not a per-channel clamp, so the hue of h is
// kept). A flat box (lo = hi) returns its centre for any h outside it (the
// final clamp: the step along the line leaves up to 1e-30 there).
#ifndef DN_CLIP_GLSL
#define DN_CLIP_GLSL

vec3 dn_clip_to_box(vec3 h, vec3 lo, vec3 hi) {
  vec3 centre = 0.5 * (lo + hi);
  vec3 extent = 0.5 * (hi - lo);
  vec3 v = h - centre;
  vec3 units = abs(v) / max(extent, vec3(1e-30));
  float m = max(units.x, max(units.y, units.z));
  return m > 1.0 ? clamp(centre + v / m, lo, hi) : h;
}

// How many of the 8 neighbours must contradict a history, on the same side
// as p, for svgf_reproject to drop it (a 3x3 highlight's corner has 3).
const int DN_REJECT_NEIGHBOURS = 3;

// History rejection (disagreement): a current luminance lp and the
// reprojected history's lh differ by more than the history's sample noise
// explains, 4 sigma, plus half the larger of the two. A reflection that
// moved against the surface's motion (a highlight that arrived or left) is
// such a pixel; stationary noise, and a static edge that the prefilter
// blurs, are not. Scale-equivariant. svgf_reproject asks it of the
// prefiltered current, of p's own and of its neighbours' values, with sigma
// from dn_history_sigma. (Luminances are >= 0 here, so once sigma reaches
// larger / 8 nothing is contradicted.)
bool dn_history_contradicted(float lp, float lh, float sigma) {
  float larger = max(lp, lh);
  return abs(lp - lh) > 4.0 * sigma + 0.5 * larger;
}

// The standard deviation of luminance moments (m1, m2), 0 where m2 - m1^2
// is below fp32's resolution of m1^2 (a young history: what is left there is
// rounding, which differs between implementations).
float dn_moments_sigma(vec2 m) {
  float v = m.y - m.x * m.x;
  return v > 1e-6 * m.x * m.x ? sqrt(v) : 0.0;
}

#endif
