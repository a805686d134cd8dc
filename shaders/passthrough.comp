#version 450
// passthrough: Radiance -> Output with format conversion only. No filtering
// and no sanitizing (values are copied as they come; fp32 -> fp16 rounds to
// nearest even and saturates a finite value at 65504, NaN and Inf stay).
//
// It walks the output word by word in a grid-stride loop, so neighbouring
// invocations touch neighbouring words and same-format copies move whole
// words: on lavapipe at 1280x720 fp16 takes 6.4 ms instead of 12.4 ms with a
// pixel-per-invocation copy (fp32 unchanged, 12 ms); on a GPU it coalesces.
// The dispatch is one invocation per pixel pair (PassSpec default).
//
// Resources: passes/passthrough.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "pass.glsl"
#include "passes/passthrough.pass"

void main() {
  const uint invocations = (frame.size.z + 1u) / 2u;
  const uint t = dn_invocation_index();
  if (t >= invocations) return;
  const uint elements = 3u * frame.size.z;                         // rgb components
  const uint out_words = OUTPUT_HALF ? (elements + 1u) / 2u : elements;
  for (uint w = t; w < out_words; w += invocations) {
    if (RADIANCE_HALF == OUTPUT_HALF) {
      result.data[w] = radiance.data[w];  // same format: the words themselves
    } else if (OUTPUT_HALF) {
      const uint e = 2u * w;
      const float hi = e + 1u < elements ? DN_LOAD(radiance, false, e + 1u) : 0.0;
      result.data[w] = dn_pack_half_saturated(vec2(DN_LOAD(radiance, false, e), hi));
    } else {
      result.data[w] = floatBitsToUint(DN_LOAD(radiance, true, w));
    }
  }
}
