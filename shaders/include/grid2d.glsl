// 2-D dispatch: one invocation per pixel of the grid a dispatch writes, in
// square workgroups whose side is specialization constant 0 (the host's
// KernelDesc::local_size_x = local_size_y; square because the SPIR-V
// reflection test admits no constant id but 0 outside a pass declaration),
// and the grid itself in push constants (dn::gpu::GridPush, 32 bytes), so a
// pass at a reduced resolution needs no constants of its own.
//
// Include instead of frame.glsl's 1-D dispatch. Every invocation of a
// workgroup must reach a barrier (tile.glsl): test dn_in_grid() after
// loading shared memory, never return before.
#ifndef DN_GRID2D_GLSL
#define DN_GRID2D_GLSL

layout(local_size_x_id = 0, local_size_y_id = 0, local_size_z = 1) in;

layout(push_constant) uniform DnGrid {
  uvec2 size;    // the grid written: width, height
  uvec2 source;  // the grid read (a pyramid's finer level); = size when the same
  uvec4 args;    // per-dispatch values: the pass's DN_GRID_ARG rows, read as dn_arg_<name>()
} dn_grid;

// Side of the square workgroup (a specialization-constant expression).
#define DN_BLOCK (gl_WorkGroupSize.x)

uvec2 dn_pixel() { return gl_GlobalInvocationID.xy; }
bool dn_in_grid(uvec2 p) { return p.x < dn_grid.size.x && p.y < dn_grid.size.y; }
// Row-major element index of pixel p in a grid of `size`.
uint dn_grid_index(uvec2 p, uvec2 size) { return p.y * size.x + p.x; }

#endif
