// Whether pixel q lies in an image of `size` (neighbourhood taps near the border).
#ifndef DN_INSIDE_GLSL
#define DN_INSIDE_GLSL

bool dn_inside(ivec2 q, uvec2 size) { return q.x >= 0 && q.y >= 0 && q.x < int(size.x) && q.y < int(size.y); }

#endif
