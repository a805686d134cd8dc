// The noise-gain histogram (image_prepare fills it, image_gain reads it): the
// ratio t = r^2 / (1.25 m^2) of a pixel's squared luminance residual to its
// squared local mean, binned in eighths of an octave of t from 2^-24 (256
// bins reach 2^8); its last element holds the gain k, as float bits.
#ifndef DN_IMAGE_GAIN_GLSL
#define DN_IMAGE_GAIN_GLSL

const float DN_GAIN_BINS_PER_OCTAVE = 8.0;
const float DN_GAIN_LOG2_MIN = -24.0;
// For noise of a normal distribution t is k times a chi-square variable of
// one degree of freedom, whose median is 0.4549 times its mean.
const float DN_GAIN_MEDIAN_TO_MEAN = 1.0 / 0.4549364;

uint dn_gain_bin(float t) {
  return uint(clamp(floor((log2(t) - DN_GAIN_LOG2_MIN) * DN_GAIN_BINS_PER_OCTAVE), 0.0, float(GAIN_BINS - 1u)));
}

#endif
