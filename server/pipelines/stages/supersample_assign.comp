#version 450
// supersample_assign: each extra sample of a pixel finds the most similar of
// the four guide pixels whose centres surround it (paper 001 §5: "by depth
// and normal"; the metric is ours, server/pipelines/stages/supersample.glsl: depth and normal
// weights times the sample's bilinear weight for the guide). A background
// sample matches background guides; a sample no guide matches (score 0)
// stays with its own pixel's guide. One invocation per pixel.
//
// Resources: supersample_assign.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "reproject.glsl"
#include "pass.glsl"
#include "generated/passes/supersample_assign.pass"

#include "supersample.glsl"

uint assign(ivec2 pos, vec3 n, float z, vec2 offset) {
  if (!dn_is_finite(n) || !dn_is_finite(offset) || isnan(z)) return DN_SAMPLE_UNUSED;
  vec2 s = vec2(pos) + 0.5 + clamp(offset, vec2(-0.5), vec2(0.5));
  ivec2 base = ivec2(floor(s - 0.5));
  bool foreground = dn_is_foreground(z);
  float best = 0.0;
  ivec2 pick = pos;
  for (int k = 0; k < 4; ++k) {
    ivec2 g = base + ivec2(k & 1, k >> 1);
    if (!dn_inside(g, frame.size.xy)) continue;
    uint gi = uint(g.y) * frame.size.x + uint(g.x);
    float zg = DN_LOAD1(depth, gi);
    bool guide_foreground = dn_is_foreground(zg);
    float w;
    if (!foreground || !guide_foreground) {
      w = foreground == guide_foreground ? 1.0 : 0.0;
    } else {
      // Sanitized (no normal: no match), so a huge normal cannot make pow() infinite.
      float c = dot(dn_sanitize_normal(n), dn_sanitize_normal(DN_LOAD3(normal, gi)));
      w = exp(-abs(z - zg) / (DN_SAMPLE_DEPTH_SCALE * max(z, zg))) * pow(max(c, 0.0), DN_SAMPLE_NORMAL_POWER);
    }
    // Proximity: the sample's bilinear weight for this guide, so that among
    // equally similar guides the nearest takes it (no drift toward one corner).
    vec2 d = abs(s - (vec2(g) + 0.5));
    w *= (1.0 - d.x) * (1.0 - d.y);
    if (w > best) {  // strict: ties keep the earlier candidate
      best = w;
      pick = g;
    }
  }
  return dn_sample_code_of(pick - pos);
}

#define DN_ASSIGN(j, n_buf, z_buf, o_buf)                                                              \
  if (SAMPLES >= j)                                                                                    \
    word |= assign(pos, DN_LOAD3(n_buf, p), DN_LOAD1(z_buf, p), \
                   DN_LOAD2(o_buf, p))                                             \
            << (4u * (j - 1u));

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  uint word = 0u;
  DN_ASSIGN(1u, normal_1, depth_1, offset_1)
  DN_ASSIGN(2u, normal_2, depth_2, offset_2)
  DN_ASSIGN(3u, normal_3, depth_3, offset_3)
  assignment.data[p] = word;
}
