// Per-frame constants (uniform buffer, set 0 binding 0 in every pass) and the
// invocation index of the linear dispatch. Mirrors dn::pipelines::FrameConstants
// in server/pipelines/graph.hpp (std140, 160 bytes).
#ifndef DN_FRAME_GLSL
#define DN_FRAME_GLSL

// Index constants of the tunables: DN_P_<pipeline>_<name>, one per row of parameters.def.
#define DN_PARAM(pipe, index, name, def, lo, hi, isint, desc) const uint DN_P_##pipe##_##name = index;
#include "parameters.def"
#undef DN_PARAM

const uint DN_FLAG_RESET = 1u;  // history must not be read this frame

layout(std140, set = 0, binding = 0) uniform FrameConstants {
  uvec4 size;       // x: width, y: height, z: pixel count, w: flags (DN_FLAG_*)
  vec4 motion;      // xy: scale that turns the client's motion vectors into pixels to the previous frame
  vec4 params[4];   // tunables, indexed by DN_P_* constants
  mat4 inverse_view_projection;  // (projection * view)^-1: clip space -> world (identity without a camera)
} frame;

#define DN_PARAM_VALUE(index) (frame.params[(index) >> 2][(index) & 3u])

// Workgroup size is specialization constant 0 in every pass.
layout(local_size_x_id = 0, local_size_y = 1, local_size_z = 1) in;

// Linear index of this invocation over a (x, y) grid of workgroups: the host
// splits large dispatches over y to stay under maxComputeWorkGroupCount[0].
uint dn_invocation_index() {
  return (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
}

#endif
