// Guide-ray supersampling (paper 001 §5, Bauszat et al. 2011; docs/pipelines.md
// "Extra samples"): the ordinary channels are sample 0, the guide ray through
// the pixel centre; each extra sample is assigned to the most similar of the
// four guide pixels nearest to it (supersample_assign), mixed into that
// guide's signal before filtering (supersample_mix, Eq. 7) and shown with
// that guide's filtered colour (supersample_resolve).
#ifndef DN_SUPERSAMPLE_GLSL
#define DN_SUPERSAMPLE_GLSL

// The assignment word of a pixel: 4 bits per extra sample (sample j at bits
// 4 (j - 1)), the guide pixel's offset from the sample's own pixel encoded as
// (dx + 1) + 3 (dy + 1), or DN_SAMPLE_UNUSED: a sample with a non-finite
// offset, normal or depth takes no part.
const uint DN_SAMPLE_UNUSED = 15u;

// Similarity of a sample to a foreground guide (the score is only ranked):
// depth relative to the larger of the two, SVGF's normal power.
const float DN_SAMPLE_DEPTH_SCALE = 0.01;
const float DN_SAMPLE_NORMAL_POWER = 128.0;

uint dn_sample_code(uint word, uint j) { return (word >> (4u * (j - 1u))) & 15u; }
uint dn_sample_code_of(ivec2 guide_offset) { return uint(guide_offset.x + 1) + 3u * uint(guide_offset.y + 1); }
ivec2 dn_sample_guide_offset(uint code) { return ivec2(int(code % 3u) - 1, int(code / 3u) - 1); }

#endif
