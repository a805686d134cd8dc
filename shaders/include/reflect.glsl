// Reflection classes and the feature distances the reflection motion search
// minimises (paper 001 §4.1-4.2, Eq. 1 and 4-5; docs/pipelines.md "reflect";
// the CPU reference is tests/pipelines/reflect/reflection_motion_reference.cpp).
// Features, two vec4 per pixel (reflect_prepare writes them, the search
// reads this frame's and the previous frame's copy):
//   [2p]     xyz: mirror: the first non-mirror hit W_p; glossy: the
//            representative ray's origin (the primary hit); w: the class
//   [2p + 1] xyz: glossy: the ray's unit direction; w: its hit distance
//            (> 0 and finite: the ray exists)
#ifndef DN_REFLECT_GLSL
#define DN_REFLECT_GLSL

const float DN_REFLECT_NONE = 0.0;    // diffuse, rough, background: primary motion
const float DN_REFLECT_MIRROR = 1.0;  // Eq. 1 on the mirror chain's hit
const float DN_REFLECT_GLOSSY = 2.0;  // Eq. 4-5 on the representative ray

const float DN_REFLECT_INVALID = 1e30;  // the distance of a candidate that cannot match

// reflect_motion's .w beside a match distance (>= 0): no match (the primary
// motion moves the history), or a mirror match rejected by the Eq. 1
// threshold (the history restarts).
const float DN_REFLECT_NO_MATCH = -1.0;
const float DN_REFLECT_REJECTED = -2.0;

// Eq. 1: |W_p - PrevW_q|.
float dn_reflect_hit_distance(vec3 wp, vec3 wq) { return length(wp - wq); }

// Eq. 4-5: approxhit(r) = r.o + r.d depth; of the two rays the one with the
// smaller depth is r_near, and the distance is that of approxhit(r_near)
// from the ray r_far: |r_far.d x (approxhit(r_near) - r_far.o)|, or its
// distance to r_far.o when it lies behind that origin (a ray, not a line: the
// line also matches hits on its extension behind the mirror). Expanded as
// (no - fo) + t nd so that two equal rays give exactly 0 (cross(d, d) = 0).
float dn_reflect_ray_distance(vec3 op, vec3 dp, float tp, vec3 oq, vec3 dq, float tq) {
  bool p_near = tp <= tq;
  vec3 no = p_near ? op : oq, nd = p_near ? dp : dq;
  float t = p_near ? tp : tq;
  vec3 fo = p_near ? oq : op, fd = p_near ? dq : dp;
  vec3 base = no - fo;
  if (dot(base, fd) + t * dot(nd, fd) < 0.0) return length(base + t * nd);
  return length(cross(fd, base) + t * cross(fd, nd));
}

bool dn_reflect_ray_exists(float t) { return t > 0.0 && t < 1e30; }

#endif
