// The reads stat_filter and stat_filter_tiled share over their bindings
// (stat_filter.pass): the critical-value table, the value a tap
// contributes and the remodulation of the result (docs/pipelines.md,
// "stat"). Include after the pass file and sanitize.glsl, before stat_gather.glsl.
#ifndef DN_STAT_FILTER_IO_GLSL
#define DN_STAT_FILTER_IO_GLSL

float dn_stat_t_squared(uint nu, bool still) {
  return t_squared.data[(still ? TABLE_SIZE : 0u) + min(nu, TABLE_SIZE) - 1u];
}

// What pixel q contributes to an average: its sanitized raw mean (the
// radiance plane, stat-temporal's accumulated raw means, or with
// DEMODULATED stat_prepare's demodulated means).
vec3 dn_stat_value(uint q) { return dn_sanitize_radiance(DN_LOAD3(radiance, q)); }

// An average of values back in radiance at pixel p: with DEMODULATED times
// p's modulation (dn_stat_modulation, from the frame's own samples).
vec3 dn_stat_remodulate(vec3 average, uint p) {
  if (!DEMODULATED) return average;
  return average * vec3(modulation.data[3u * p], modulation.data[3u * p + 1u], modulation.data[3u * p + 2u]);
}

#endif
