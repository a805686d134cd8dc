#version 450
// reflect_motion (reflect): reflection motion vectors by diamond search
// (paper 001 Alg. 1, Eq. 1-5; docs/pipelines.md "reflect"). For a mirror or
// glossy pixel p, the previous pixel q whose features (reflect.glsl) are
// nearest to p's: starts at p, at the pixel nearest p + primary motion and,
// with VIRTUAL_START, at the pixel nearest p + the virtual point's motion
// (reflect_prepare);
// a large diamond scaled FIRST_STEP -> ... -> 1 moved while it strictly
// improves; one small diamond; then Eq. 2-3 sub-pixel refinement over the
// best 2x2 block. Candidates off-screen, of another class, or (glossy)
// without a ray do not match. Mirrors the CPU reference
// tests/pipelines/reflect/reflection_motion_reference.cpp step by step.
// One invocation per pixel.
//
// Resources: reflect_motion.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "reproject.glsl"
#include "pass.glsl"
#include "generated/passes/reflect_motion.pass"

#include "reflect.glsl"

vec4 pa, pb;  // p's features

float distance_to(ivec2 q) {
  if (!dn_inside(q, frame.size.xy)) return DN_REFLECT_INVALID;
  uint qi = uint(q.y) * frame.size.x + uint(q.x);
  vec4 qa = prev_features_at(2u * qi);
  if (qa.w != pa.w) return DN_REFLECT_INVALID;
  if (pa.w == DN_REFLECT_MIRROR) return dn_reflect_hit_distance(pa.xyz, qa.xyz);
  vec4 qb = prev_features_at(2u * qi + 1u);
  if (!dn_reflect_ray_exists(qb.w)) return DN_REFLECT_INVALID;
  return dn_reflect_ray_distance(pa.xyz, pb.xyz, pb.w, qa.xyz, qb.xyz, qb.w);
}

ivec2 best;
float best_distance;

void consider(ivec2 q) {
  float d = distance_to(q);
  if (d < best_distance) {
    best = q;
    best_distance = d;
  }
}

const ivec2 LARGE_AXES[4] = ivec2[4](ivec2(2, 0), ivec2(-2, 0), ivec2(0, 2), ivec2(0, -2));
const ivec2 LARGE_DIAGONALS[4] = ivec2[4](ivec2(1, 1), ivec2(-1, 1), ivec2(1, -1), ivec2(-1, -1));
const ivec2 SMALL[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));

// A start at the pixel nearest pos + mv, for a usable motion.
void consider_start(ivec2 pos, vec2 mv) {
  if (dn_motion_usable(mv)) consider(ivec2(floor(vec2(pos) + mv + 0.5)));
}

void diamond_search(ivec2 pos, vec2 mv, vec2 vmv) {
  best = pos;
  best_distance = DN_REFLECT_INVALID;
  consider(pos);
  consider_start(pos, mv);
  if (VIRTUAL_START) consider_start(pos, vmv);
  int step = FIRST_STEP;
  ivec2 centre = best;
  for (int it = 0; it < MAX_ITERATIONS; ++it) {
    for (int k = 0; k < 4; ++k) consider(centre + (DIAGONALS ? LARGE_DIAGONALS[k] : LARGE_AXES[k]) * step);
    if (best == centre) {
      if (step == 1) break;
      step /= 2;
    }
    centre = best;
  }
  for (int k = 0; k < 4; ++k) consider(centre + SMALL[k]);
}

// Eq. 2-3: among the four 2x2 blocks holding the match, the one of smallest
// summed distance (blocks with a pixel that cannot match are skipped); each
// pixel weighted by the product of the other three's distances, divided by
// the match's first so the products stay in range. An exact match returns
// the pixel; no block, or all weights 0 (two zero distances), falls back to
// the integer match.
vec2 refine_subpixel() {
  vec2 at = vec2(best);
  if (best_distance == 0.0) return at;
  float best_sum = DN_REFLECT_INVALID;
  ivec2 origin = best;
  vec4 d_best = vec4(0.0);
  for (int oy = -1; oy <= 0; ++oy)
    for (int ox = -1; ox <= 0; ++ox) {
      ivec2 o = best + ivec2(ox, oy);
      vec4 d = vec4(distance_to(o), distance_to(o + ivec2(1, 0)), distance_to(o + ivec2(0, 1)),
                    distance_to(o + ivec2(1, 1)));
      if (any(greaterThanEqual(d, vec4(DN_REFLECT_INVALID)))) continue;
      d /= best_distance;
      float sum = d.x + d.y + d.z + d.w;
      if (sum < best_sum) {
        best_sum = sum;
        origin = o;
        d_best = d;
      }
    }
  if (!(best_sum < DN_REFLECT_INVALID)) return at;
  vec4 w = vec4(d_best.y * d_best.z * d_best.w, d_best.x * d_best.z * d_best.w, d_best.x * d_best.y * d_best.w,
                d_best.x * d_best.y * d_best.z);
  float total = w.x + w.y + w.z + w.w;
  if (!(total > 0.0) || !dn_is_finite(total)) return at;
  w /= total;
  return vec2(origin) + vec2(w.y + w.w, w.z + w.w);
}

// Eq. 1 threshold (mirror_match_threshold > 0): the match is kept when its
// distance is within the threshold times the spacing of the previous
// frame's hits at the match (the smallest distance to an axis neighbour's
// hit of the same class; no neighbour: kept).
bool mirror_match_kept(ivec2 q, float d) {
  float threshold = DN_PARAM_VALUE(reflect, mirror_match_threshold);
  if (!(threshold > 0.0)) return true;
  vec3 wq = prev_features_at(2u * (uint(q.y) * frame.size.x + uint(q.x))).xyz;
  float spacing = DN_REFLECT_INVALID;
  for (int k = 0; k < 4; ++k) {
    ivec2 r = q + SMALL[k];
    if (!dn_inside(r, frame.size.xy)) continue;
    vec4 a = prev_features_at(2u * (uint(r.y) * frame.size.x + uint(r.x)));
    if (a.w == DN_REFLECT_MIRROR) spacing = min(spacing, dn_reflect_hit_distance(wq, a.xyz));
  }
  return !(spacing < DN_REFLECT_INVALID) || d <= threshold * spacing;
}

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  vec2 mv = DN_LOAD2(motion, p) * frame.motion.xy;
  pa = features_at(2u * p);
  pb = features_at(2u * p + 1u);
  bool searched = pa.w != DN_REFLECT_NONE && (pa.w == DN_REFLECT_MIRROR || dn_reflect_ray_exists(pb.w)) &&
                  (frame.size.w & DN_FLAG_RESET) == 0u;
  float match = DN_REFLECT_NO_MATCH;
  if (searched) {
    diamond_search(pos, mv, VIRTUAL_START ? virtual_motion.data[p] : vec2(DN_REFLECT_INVALID));
    if (best_distance < DN_REFLECT_INVALID) {
      if (pa.w == DN_REFLECT_MIRROR && !mirror_match_kept(best, best_distance)) {
        match = DN_REFLECT_REJECTED;
      } else {
        mv = refine_subpixel() - vec2(pos);
        match = best_distance;
      }
    }
  }
  result.data[p] = vec4(mv, pa.w, match);
}
