#version 450
// sample_summary: how many input frames each pixel's output rests on, over
// the frame: the smallest count and a histogram the host reads the median
// from (server/pipelines/sample_summary.cpp). Each invocation walks RUN
// consecutive pixels and adds a run of equal bins at once (neighbours mostly
// share one, and atomics on one shared word serialise, on lavapipe as on a
// GPU); each workgroup adds its non-empty bins to the summary once.
//
// Resources: sample_summary.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "pass.glsl"
#include "sample_bins.glsl"
#include "generated/passes/sample_summary.pass"

shared uint bins[DN_SAMPLE_BINS];
shared uint group_max_inverse;

void main() {
  for (uint b = gl_LocalInvocationID.x; b < DN_SAMPLE_BINS; b += gl_WorkGroupSize.x) bins[b] = 0u;
  if (gl_LocalInvocationID.x == 0u) group_max_inverse = 0u;
  barrier();

  const uint first = dn_invocation_index() * RUN;
  uint run_bin = 0u, run_length = 0u, max_inverse = 0u;
  for (uint k = 0u; k < RUN; ++k) {
    const uint p = first + k;
    if (p >= frame.size.z) break;
    float count = COUNTS ? counts.data[p] : history_at(p).w;
    if (STILL) count = max(count, still_at(p).w);
    const uint n = uint(clamp(count, 0.0, 4294967040.0) + 0.5);
    const uint bin = dn_sample_bin(n);
    max_inverse = max(max_inverse, 0xffffffffu - n);
    if (run_length > 0u && bin != run_bin) {
      atomicAdd(bins[run_bin], run_length);
      run_length = 0u;
    }
    run_bin = bin;
    ++run_length;
  }
  if (run_length > 0u) atomicAdd(bins[run_bin], run_length);
  if (max_inverse != 0u) atomicMax(group_max_inverse, max_inverse);
  barrier();

  for (uint b = gl_LocalInvocationID.x; b < DN_SAMPLE_BINS; b += gl_WorkGroupSize.x)
    if (bins[b] != 0u) atomicAdd(summary.data[1u + b], bins[b]);
  if (gl_LocalInvocationID.x == 0u && group_max_inverse != 0u) atomicMax(summary.data[0], group_max_inverse);
}
