// The histogram bins of sample_summary (mirrored by server/pipelines/
// sample_summary.cpp): one bin per count below 32, then 16 per power of two
// up to 2^21 (larger counts fall in the last bin).
#ifndef DN_SAMPLE_BINS_GLSL
#define DN_SAMPLE_BINS_GLSL

const uint DN_SAMPLE_BINS = 32u + 16u * 16u;

uint dn_sample_bin(uint n) {
  if (n < 32u) return n;
  const uint octave = min(uint(findMSB(n)), 20u);  // 5 ... 20
  const uint sub = n >= (1u << 21) ? 15u : (n >> (octave - 4u)) & 15u;
  return 32u + (octave - 5u) * 16u + sub;
}

#endif
