// Per-frame constants (set 0 binding 0 in every pass) and the
// invocation index of the linear dispatch. Mirrors dn::pipelines::FrameConstants
// in server/pipelines/frame_constants.hpp (std140; the spirv.* tests compare
// the offsets).
#ifndef DN_FRAME_GLSL
#define DN_FRAME_GLSL

// The tunables: one float member <group>_<name> per row of parameters.def, in
// row order (std140 packs consecutive floats; C++: dn::pipelines::Parameters).
struct DnParameters {
#define DN_PARAM(group, name, def, lo, hi, isint, desc) float group##_##name;
#include "generated/parameters.def"
#undef DN_PARAM
};

const uint DN_FLAG_RESET = 1u;  // history must not be read this frame

// A read-only storage buffer, not a uniform block: lavapipe (Mesa 22.3)
// inlines the values of small uniform blocks into the shader and keeps a
// compiled variant per set of values, so constants that change every frame
// recompiled every pass at each dispatch and grew the server by 0.3-3 MB a
// frame (docs/results.md, "Soak: 64 sessions x 10 minutes").
layout(std140, set = 0, binding = 0) readonly buffer FrameConstants {
  uvec4 size;       // x: width, y: height, z: pixel count, w: flags (DN_FLAG_*)
  vec4 motion;      // xy: scale that turns the client's motion vectors into pixels to the previous frame
  mat4 inverse_view_projection;  // (projection * view)^-1: clip space -> world (identity without a camera)
  mat4 previous_view_projection; // projection * view of the previous frame: world -> its clip space (identity before one)
  DnParameters params;           // last: it grows with parameters.def
} frame;

// The value of tunable `name` of parameter group `group` (a row of parameters.def).
#define DN_PARAM_VALUE(group, name) (frame.params.group##_##name)

// Workgroup size is specialization constant 0 in every pass. A pass over a
// 2-D grid includes grid2d.glsl first, which declares its own.
#ifndef DN_GRID2D_GLSL
layout(local_size_x_id = 0, local_size_y = 1, local_size_z = 1) in;

// Linear index of this invocation over a (x, y) grid of workgroups: the host
// splits large dispatches over y to stay under maxComputeWorkGroupCount[0].
uint dn_invocation_index() {
  return (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
}
#endif

#endif
