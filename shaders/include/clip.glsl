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
// reprojected history's lh differ by more than the history's own sample
// noise explains, 4 sigma = 4 sqrt(m2 - m1^2), plus half the larger of the
// two. A reflection that moved against the surface's motion (a highlight
// that arrived or left) is such a pixel; stationary noise, and a static edge
// that the prefilter blurs, are not. Scale-equivariant. svgf_reproject asks
// it of the prefiltered current, of p's own and of its neighbours' values.
bool dn_history_contradicted(float lp, float lh, vec2 moments) {
  float larger = max(lp, lh);
  float sigma = min(sqrt(max(0.0, moments.y - moments.x * moments.x)), 0.125 * larger);
  return abs(lp - lh) > 4.0 * sigma + 0.5 * larger;
}

#endif
