// The reads and the write stat_filter and stat_filter_tiled share over their
// bindings (passes/stat_filter.pass): the critical-value table, the value a
// tap contributes and the remodulation of the result (docs/pipelines.md,
// "stat"). Include after the pass file and sanitize.glsl, before stat_gather.glsl.
#ifndef DN_STAT_FILTER_IO_GLSL
#define DN_STAT_FILTER_IO_GLSL

float dn_stat_t_squared(uint nu) { return t_squared.data[min(nu, TABLE_SIZE) - 1u]; }

// The statistics are over demodulated samples (the session's parameter):
// the filter averages radiance / albedo and remodulates.
bool dn_stat_demodulated() { return DN_PARAM_VALUE(stat, demodulated) != 0.0; }

// What pixel q contributes to an average: its sanitized raw mean, divided by
// its guarded albedo when the statistics are demodulated and the raw means
// are not yet (RAW_DEMODULATED: stat-temporal's accumulators hold
// demodulated means already).
vec3 dn_stat_value(uint q) {
  vec3 raw = dn_sanitize_radiance(DN_LOAD3(radiance, RADIANCE_HALF, q));
  if (!dn_stat_demodulated() || RAW_DEMODULATED) return raw;
  return raw / dn_guarded_albedo(DN_LOAD3(albedo, ALBEDO_HALF, q));
}

// An average of values back in radiance at a pixel of albedo albedo_p.
vec3 dn_stat_remodulate(vec3 average, vec3 albedo_p) {
  return dn_stat_demodulated() ? average * dn_guarded_albedo(albedo_p) : average;
}

#endif
