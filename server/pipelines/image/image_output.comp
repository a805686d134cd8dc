#version 450
// image_output: the filtered colour, each component held within harm_guard
// standard deviations of the pixel's estimated noise from its own input
// (what the filter takes away beyond that is taken for signal, not noise:
// a reflection, a highlight's edge), multiplied by the albedo again. One
// invocation per pixel.
//
// Resources: image_output.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "pass.glsl"
#include "sanitize.glsl"
#include "generated/passes/image_output.pass"

void main() {
  const uint pi = dn_invocation_index();
  if (pi >= frame.size.z) return;
  const vec4 n = noisy_at(pi);
  vec3 c = filtered_at(pi).rgb;
  const float k = DN_PARAM_VALUE(image, harm_guard);
  if (k > 0.0) {
    const float reach = k * sqrt(max(n.w, 0.0));
    c = n.rgb + clamp(c - n.rgb, vec3(-reach), vec3(reach));
  }
  c = max(c, vec3(0.0)) * (HAS_ALBEDO ? dn_guarded_albedo(DN_LOAD3(albedo, pi)) : vec3(1.0));
  result.data[3u * pi] = floatBitsToUint(c.r);
  result.data[3u * pi + 1u] = floatBitsToUint(c.g);
  result.data[3u * pi + 2u] = floatBitsToUint(c.b);
}
