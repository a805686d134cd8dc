#version 450
// svgf_taa: the optional final temporal anti-aliasing blend (taa_alpha > 0;
// docs/pipelines.md, "svgf in detail", 5). Per pixel: where svgf_remodulate
// found a usable history, the reprojected previous final output is clamped
// per RGB channel to the min/max of the current colour over the 3x3
// neighbourhood (the taps inside the image) and out = mix(clamped, current,
// taa_alpha); elsewhere out = current. out goes to Output (session format)
// and to the TAA history (fp32). One invocation per pixel pair.
//
// Bindings: 0 FrameConstants, 1 TAA current vec4(rgb, history usable),
//   2 TAA previous vec4(reprojected rgb, 0) (both written by svgf_remodulate),
//   3 output, 4 TAA history (3 fp32 per pixel; read by svgf_remodulate only)
// Specialization: 0 workgroup size, 1 output is fp16
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"

layout(constant_id = 1) const bool OUTPUT_HALF = false;

layout(std430, set = 0, binding = 1) readonly buffer TaaCurrent { vec4 data[]; } current;
layout(std430, set = 0, binding = 2) readonly buffer TaaPrevious { vec4 data[]; } previous;
layout(std430, set = 0, binding = 3) writeonly buffer OutputPlane { uint data[]; } result;
layout(std430, set = 0, binding = 4) writeonly buffer TaaHistory { float data[]; } history;

vec3 blend(uint p) {
  vec4 c = current.data[p];
  vec3 out_c = c.rgb;
  if (c.a > 0.5) {
    ivec2 size = ivec2(frame.size.xy);
    ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
    vec3 lo = c.rgb, hi = c.rgb;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        ivec2 q = pos + ivec2(dx, dy);
        if (q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) continue;
        vec3 v = current.data[uint(q.y) * frame.size.x + uint(q.x)].rgb;
        lo = min(lo, v);
        hi = max(hi, v);
      }
    vec3 prev = clamp(previous.data[p].rgb, lo, hi);
    out_c = mix(prev, c.rgb, DN_PARAM_VALUE(DN_P_svgf_taa_alpha));
  }
  history.data[3u * p] = out_c.r;
  history.data[3u * p + 1u] = out_c.g;
  history.data[3u * p + 2u] = out_c.b;
  return out_c;
}

void main() {
  uint pair = dn_invocation_index();
  uint n = frame.size.z;
  uint p0 = 2u * pair;
  if (p0 >= n) return;
  bool has_b = p0 + 1u < n;
  vec3 a = blend(p0);
  vec3 b = vec3(0.0);
  if (has_b) b = blend(p0 + 1u);
  DN_STORE_RGB_PAIR(result, OUTPUT_HALF, pair, a, b, has_b)
}
