// Plane access. A plane is a buffer of uint words bound as `read` or `texel`
// (loads go through name_at, so either works: passes gather planes through
// r32ui texel views, lavapipe's faster scattered read) holding fp32
// components interleaved per pixel, row-major. Client planes reach the device
// as fp32 whatever their wire format (server/pipelines/wire_format.hpp), so
// no pass depends on what a client sends.
//
// GLSL cannot pass buffers to functions, hence macros taking the block
// instance name. Element e of a plane with c components: pixel * c + component.
#ifndef DN_PLANE_GLSL
#define DN_PLANE_GLSL

#define DN_LOAD(buf, e) uintBitsToFloat(buf##_at((e)))

#define DN_LOAD1(buf, pixel) DN_LOAD(buf, (pixel))
#define DN_LOAD2(buf, pixel) vec2(DN_LOAD(buf, 2u * (pixel)), DN_LOAD(buf, 2u * (pixel) + 1u))
#define DN_LOAD3(buf, pixel) \
  vec3(DN_LOAD(buf, 3u * (pixel)), DN_LOAD(buf, 3u * (pixel) + 1u), DN_LOAD(buf, 3u * (pixel) + 2u))

// Stores the RGB values of pixels 2*pair and 2*pair+1 (only pixel a when
// has_b is false: an odd pixel count's last pair).
#define DN_STORE_RGB_PAIR(buf, pair, a, b, has_b) \
  {                                               \
    uint dn_e = 6u * (pair);                      \
    buf.data[dn_e] = floatBitsToUint((a).x);      \
    buf.data[dn_e + 1u] = floatBitsToUint((a).y); \
    buf.data[dn_e + 2u] = floatBitsToUint((a).z); \
    if (has_b) {                                  \
      buf.data[dn_e + 3u] = floatBitsToUint((b).x); \
      buf.data[dn_e + 4u] = floatBitsToUint((b).y); \
      buf.data[dn_e + 5u] = floatBitsToUint((b).z); \
    }                                             \
  }

#endif
