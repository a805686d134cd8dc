// The current frame's demodulated signal at a pixel, as the SVGF chain
// filters it: sanitized, minus what the primary hit emits
// (SUBTRACT_EMISSION), divided by the guarded modulator (DEMODULATE). One
// definition for every pass that reads a signal plane (svgf_reproject,
// svgf_clip_prefilter). Requires, declared before the include: the planes
// `signal`, `modulator`, `emission` ({ uint data[]; }), the bools
// DEMODULATE and SUBTRACT_EMISSION, plus plane.glsl, sanitize.glsl and svgf_guards.glsl.
#ifndef DN_SVGF_SIGNAL_GLSL
#define DN_SVGF_SIGNAL_GLSL

vec3 dn_svgf_current(uint p) {
  vec3 c = dn_sanitize_radiance(DN_LOAD3(signal, p));
  if (SUBTRACT_EMISSION) c = max(c - dn_sanitize_radiance(DN_LOAD3(emission, p)), vec3(0.0));
  vec3 a = DEMODULATE ? dn_guarded_albedo(DN_LOAD3(modulator, p)) : vec3(1.0);
  return c / a;
}

#endif
