// Fill from the nearest pixels that have a value (progressive below one
// sample per pixel: unsampled background pixels in svgf_reproject, pixels
// still without data after the last a-trous iteration; docs/pipelines.md,
// "progressive"): the mean over the smallest square ring around p, radius 1
// to DN_FILL_RADIUS, that holds any source pixel. The including shader
// defines, before the include, bool dn_fill_source(ivec2 q, out vec3 value).
// Needs reproject.glsl (dn_inside) and frame.glsl or grid2d.glsl for the size.
#ifndef DN_RING_FILL_GLSL
#define DN_RING_FILL_GLSL

// 8: a stratified schedule down to 1/64 spp has a sample in every 8x8 tile
// each frame, so a ring of radius 8 always reaches one.
const int DN_FILL_RADIUS = 8;

bool dn_ring_fill(ivec2 p, uvec2 size, out vec3 mean) {
  mean = vec3(0.0);
  for (int r = 1; r <= DN_FILL_RADIUS; ++r) {
    vec3 sum = vec3(0.0);
    int count = 0;
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; dx += (abs(dy) == r ? 1 : 2 * r)) {
        ivec2 q = p + ivec2(dx, dy);
        vec3 v;
        if (dn_inside(q, size) && dn_fill_source(q, v)) {
          sum += v;
          ++count;
        }
      }
    if (count > 0) {
      mean = sum / float(count);
      return true;
    }
  }
  return false;
}

#endif
