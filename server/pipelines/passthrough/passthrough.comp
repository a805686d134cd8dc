#version 450
// passthrough: Radiance -> Output. No filtering; finite values are copied as
// they come and a non-finite one (NaN, +-Inf) becomes 0, so no output is ever
// non-finite. Planes are fp32 here; the wire formats are converted at upload
// and readback (wire_format.hpp).
//
// It walks the output word by word in a grid-stride loop, so neighbouring
// invocations touch neighbouring words; on a GPU it coalesces. The dispatch
// is one invocation per pixel pair (PassSpec default).
//
// Resources: passthrough.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "plane.glsl"
#include "pass.glsl"
#include "generated/passes/passthrough.pass"

void main() {
  const uint invocations = (frame.size.z + 1u) / 2u;
  const uint t = dn_invocation_index();
  if (t >= invocations) return;
  const uint words = 3u * frame.size.z;  // rgb components
  for (uint w = t; w < words; w += invocations) {
    const uint v = radiance.data[w];
    result.data[w] = (v & 0x7f800000u) == 0x7f800000u ? 0u : v;
  }
}
