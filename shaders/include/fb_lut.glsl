// The F_beta table (BRDF pre-integration, paper 000 Eq. 7/8; docs/pipelines.md,
// "F_β LUT"): DN_FB_LUT_SIZE² texels of vec2 (A, B), fp32, so that
// F_beta = F0 · A + B for isotropic GGX with height-correlated Smith G2 and
// Schlick Fresnel. Texel (i, j) (column i, row j, index j · DN_FB_LUT_SIZE + i)
// holds cos θ_o = (i + 0.5) / DN_FB_LUT_SIZE and GGX α = (j + 0.5) / DN_FB_LUT_SIZE
// (α, not perceptual roughness: the protocol's `roughness` channel is α).
// Computed once per device by fb_lut.comp (server/pipelines/stages/fb_lut.hpp).
//
// Using the lookup: declare the table before including this file, as a
// binding named fb_lut with element vec2 in the pass declaration
// (passes/<pass>.pass: DN_BINDING(n, fb_lut, vec2, texel, required)).
// Defining DN_FB_LUT_NO_LOOKUP leaves out the lookup (the generator does).
#ifndef DN_FB_LUT_GLSL
#define DN_FB_LUT_GLSL

// Texels per axis. The one GLSL definition; the C++ one is
// dn::pipelines::kFbLutSize, and the test FbLut.GlslSizeMatchesCpp checks
// that the two agree.
#define DN_FB_LUT_SIZE 256

// Axis value at texel centre i: cos θ_o of column i, α of row i.
float dn_fb_lut_axis(uint i) { return (float(i) + 0.5) / float(DN_FB_LUT_SIZE); }

#ifndef DN_FB_LUT_NO_LOOKUP

// Continuous texel coordinate of an axis value, clamped to the first/last
// texel centre; NaN reads as the first texel (tested on the bits, immune to
// fast-math folding), +Inf as the last.
float dn_fb_lut_coord(float x) {
  if ((floatBitsToUint(x) & 0x7fffffffu) > 0x7f800000u) x = 0.0;
  x = x * float(DN_FB_LUT_SIZE) - 0.5;
  return clamp(x, 0.0, float(DN_FB_LUT_SIZE - 1));
}

// (A, B) at (cos θ_o, GGX α), bilinear between texel centres, clamped at the
// edges (constant beyond the first/last centre: cos θ_o < 0.5/256 reads the
// first column, α < 0.5/256 the first row, values above 1 the last).
vec2 dn_fb_lut(float cos_o, float alpha) {
  const uint n = uint(DN_FB_LUT_SIZE);
  float x = dn_fb_lut_coord(cos_o);
  float y = dn_fb_lut_coord(alpha);
  uint i0 = min(uint(x), n - 2u);
  uint j0 = min(uint(y), n - 2u);
  float tx = x - float(i0);
  float ty = y - float(j0);
  uint base = j0 * n + i0;
  vec2 lo = mix(fb_lut_at(base), fb_lut_at(base + 1u), tx);
  vec2 hi = mix(fb_lut_at(base + n), fb_lut_at(base + n + 1u), tx);
  return mix(lo, hi, ty);
}
#endif  // DN_FB_LUT_NO_LOOKUP

#endif  // DN_FB_LUT_GLSL
