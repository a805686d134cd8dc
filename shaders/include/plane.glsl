// Plane access. A plane is a buffer of uint words bound as `read` or `texel`
// (loads go through name_at, so either works: passes gather planes through
// r32ui texel views, lavapipe's faster scattered read) holding the client's
// bytes verbatim: components interleaved per pixel,
// row-major, each component little-endian fp16 or fp32. Whether a plane is
// fp16 is a specialization constant of the pass (a bool), so the branch folds
// away when the pipeline is specialised.
//
// GLSL cannot pass buffers to functions, hence macros taking the block
// instance name. Element e of a plane with c components: pixel * c + component.
#ifndef DN_PLANE_GLSL
#define DN_PLANE_GLSL

// fp16 element e lives in the low (even e) or high (odd e) half of word e / 2.
#define DN_LOAD(buf, is_half, e) \
  ((is_half) ? unpackHalf2x16(buf##_at((e) >> 1u) >> (((e) & 1u) << 4u)).x : uintBitsToFloat(buf##_at((e))))

#define DN_LOAD1(buf, is_half, pixel) DN_LOAD(buf, is_half, (pixel))
#define DN_LOAD2(buf, is_half, pixel) \
  vec2(DN_LOAD(buf, is_half, 2u * (pixel)), DN_LOAD(buf, is_half, 2u * (pixel) + 1u))
#define DN_LOAD3(buf, is_half, pixel) \
  vec3(DN_LOAD(buf, is_half, 3u * (pixel)), DN_LOAD(buf, is_half, 3u * (pixel) + 1u), DN_LOAD(buf, is_half, 3u * (pixel) + 2u))

// fp32 -> fp16 output: round to nearest even (packHalf2x16 on the devices
// we test), but a finite value beyond the largest finite half (65504)
// saturates to it instead of becoming Inf. NaN and Inf stay as they are
// (only passthrough, which does not sanitize, can hold them).
const float DN_HALF_MAX = 65504.0;
float dn_saturate_half(float x) {
  return (floatBitsToUint(x) & 0x7f800000u) != 0x7f800000u ? clamp(x, -DN_HALF_MAX, DN_HALF_MAX) : x;
}
uint dn_pack_half_saturated(vec2 v) { return packHalf2x16(vec2(dn_saturate_half(v.x), dn_saturate_half(v.y))); }

// Stores the RGB values of pixels 2*pair and 2*pair+1. An fp16 RGB pair is
// exactly three 32-bit words, so no two invocations ever write the same word.
// When has_b is false (odd pixel count, last pair) only pixel a is written; in
// fp16 its last word's high half is padding (buffers are rounded up to 4 bytes).
// fp32 -> fp16 saturates (dn_pack_half_saturated).
#define DN_STORE_RGB_PAIR(buf, is_half, pair, a, b, has_b)                 \
  {                                                                        \
    if (is_half) {                                                         \
      uint dn_w = 3u * (pair);                                             \
      buf.data[dn_w] = dn_pack_half_saturated((a).xy);                     \
      buf.data[dn_w + 1u] = dn_pack_half_saturated(vec2((a).z, (has_b) ? (b).x : 0.0)); \
      if (has_b) buf.data[dn_w + 2u] = dn_pack_half_saturated((b).yz);     \
    } else {                                                               \
      uint dn_e = 6u * (pair);                                             \
      buf.data[dn_e] = floatBitsToUint((a).x);                             \
      buf.data[dn_e + 1u] = floatBitsToUint((a).y);                        \
      buf.data[dn_e + 2u] = floatBitsToUint((a).z);                        \
      if (has_b) {                                                         \
        buf.data[dn_e + 3u] = floatBitsToUint((b).x);                      \
        buf.data[dn_e + 4u] = floatBitsToUint((b).y);                      \
        buf.data[dn_e + 5u] = floatBitsToUint((b).z);                      \
      }                                                                    \
    }                                                                      \
  }

#endif
