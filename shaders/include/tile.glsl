// Shared-memory tiles for wide gathers: each workgroup (grid2d.glsl) loads
// the (DN_BLOCK + 2·apron)² pixels around its block once, so a gather of
// radius <= apron reads shared memory instead of (2R+1)² buffer loads per
// pixel. Pixels beyond the grid are clamped to its border (edge replication);
// dn_tile_inside() tells a kernel which taps were clamped so it can drop them.
//
// Before the include define DN_TILE_APRON (a uint constant expression,
// usually a specialization constant) and optionally DN_TILE_T (the element
// type, vec4 by default), and declare or define
//   DN_TILE_T dn_tile_fetch(ivec2 p);   // pixel p of the source, always inside it
// Shared memory: (DN_BLOCK + 2·DN_TILE_APRON)² · sizeof(DN_TILE_T) bytes
// (32 KiB on lavapipe: block 16 and apron 8 of vec4 take 16 KiB; the stat
// denoiser's radius 20 fits as float or vec2 tiles, 12.5 / 25 KiB at block 16,
// not as vec4).
#ifndef DN_TILE_GLSL
#define DN_TILE_GLSL

#ifndef DN_TILE_T
#define DN_TILE_T vec4
#endif

const uint DN_TILE_SIDE = DN_BLOCK + 2u * DN_TILE_APRON;
shared DN_TILE_T dn_tile[DN_TILE_SIDE * DN_TILE_SIDE];

DN_TILE_T dn_tile_fetch(ivec2 p);

// Pixel of tile element (0, 0): the block's corner minus the apron.
ivec2 dn_tile_origin() { return ivec2(gl_WorkGroupID.xy * DN_BLOCK) - int(DN_TILE_APRON); }

// Loads the tile of this workgroup from a source grid of `size`, then waits
// for the whole workgroup. Call from uniform control flow (every invocation).
void dn_tile_load(uvec2 size) {
  const ivec2 last = ivec2(size) - 1;
  const ivec2 origin = dn_tile_origin();
  for (uint i = gl_LocalInvocationIndex; i < DN_TILE_SIDE * DN_TILE_SIDE; i += DN_BLOCK * DN_BLOCK) {
    ivec2 p = origin + ivec2(i % DN_TILE_SIDE, i / DN_TILE_SIDE);
    dn_tile[i] = dn_tile_fetch(clamp(p, ivec2(0), last));
  }
  barrier();
}

// The value at this invocation's pixel + offset (|offset| <= apron per axis).
DN_TILE_T dn_tile_at(ivec2 offset) {
  uvec2 t = uvec2(ivec2(gl_LocalInvocationID.xy) + offset + int(DN_TILE_APRON));
  return dn_tile[t.y * DN_TILE_SIDE + t.x];
}

// Whether this invocation's pixel + offset lies inside a grid of `size`
// (false: dn_tile_at(offset) holds a clamped border pixel).
bool dn_tile_inside(ivec2 offset, uvec2 size) {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy) + offset;
  return p.x >= 0 && p.y >= 0 && p.x < int(size.x) && p.y < int(size.y);
}

#endif
