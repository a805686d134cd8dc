// Geometry access of svgf_reproject, the only svgf pass that reads the depth
// and normal planes (the later passes read its guide; docs/pipelines.md, "svgf
// in detail"): guards (svgf_guards.glsl) and the per-pixel geometry gradients.
// Requires, declared before the include: the planes `depth` and `normal`
// ({ uint data[]; }), plus
// frame.glsl, plane.glsl, sanitize.glsl and luminance.glsl.
#ifndef DN_SVGF_GLSL
#define DN_SVGF_GLSL

#include "svgf_guards.glsl"
#include "inside.glsl"

float dn_svgf_depth(uint p) { return DN_LOAD1(depth, p); }
vec3 dn_svgf_normal(uint p) { return dn_sanitize_normal(DN_LOAD3(normal, p)); }

// Geometry gradients of a foreground pixel: per axis the one-sided difference
// of smaller magnitude over the neighbours that are inside and foreground
// (0 if none), then the max over the two axes. x: depth, y: normal distance.
vec2 dn_svgf_gradients(ivec2 pos, float z, vec3 n) {
  ivec2 size = ivec2(frame.size.xy);
  vec2 result = vec2(0.0);
  for (int axis = 0; axis < 2; ++axis) {
    float best_z = 1e30, best_n = 1e30;
    bool any = false;
    for (int side = -1; side <= 1; side += 2) {
      ivec2 q = pos;
      q[axis] += side;
      if (!dn_inside(q, uvec2(size))) continue;
      uint qi = uint(q.y) * uint(size.x) + uint(q.x);
      float zq = dn_svgf_depth(qi);
      if (!dn_is_foreground(zq)) continue;
      any = true;
      best_z = min(best_z, abs(zq - z));
      best_n = min(best_n, distance(dn_svgf_normal(qi), n));
    }
    if (any) result = max(result, vec2(best_z, best_n));
  }
  return result;
}

#endif
