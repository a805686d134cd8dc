#version 450
// svgf_remodulate: Output = filtered demodulated colour * guarded albedo
// (+ the filtered specular in split mode, + sanitized emission, never
// filtered: a still pixel's running mean of it) as fp32
// (docs/pipelines.md, "svgf in detail", 4). One invocation per pixel
// pair.
// With TAA (taa_alpha or taa_static_alpha > 0: TAA) it writes, instead of Output, the
// current colour and the bilinearly reprojected previous final output for
// svgf_taa (docs/pipelines.md, "svgf in detail", 5): the TAA history is read
// only here and rewritten only by svgf_taa, so one persistent copy suffices.
//
// Resources: svgf_remodulate.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "luminance.glsl"
#include "reproject.glsl"
#include "pass.glsl"
#include "generated/passes/svgf_remodulate.pass"

#include "svgf_guards.glsl"

// Do no harm (svgf harm_guard g): the filtered value f may leave the pixel's
// own temporal mean m (variance v) by g standard deviations; beyond, the
// MSE-optimal blend of the unbiased m and the biased f under the bias
// estimate d^2 - g^2 v. Only where the mean has DN_GUARD_MIN_LENGTH samples,
// so that v is the pixel's own (younger pixels' is a spatial estimate, and a
// lone bright sample may be a firefly); pixels without data keep f.
const float DN_GUARD_MIN_LENGTH = 4.0;
// converge_still k: where a pixel is still and its running mean of its own
// samples holds DN_STILL_MIN_SAMPLES or more, that mean is the target
// instead, with a = k standard deviations of it (a sample's variance over its
// samples), and beyond a the deviation shrinks as (a / Y(f - m))^3, not ^1:
// that mean's noise is not filtered, so a value just beyond a moves little,
// and a bias well beyond it (a blurred edge) is taken out nearly whole. The
// mean tends to the reference, and the output with it. Its weight:
// dn_still_weight (reproject.glsl).
// The guard's moving target of signal s: vec4(m.rgb, a^2; negative: no data).
vec4 dn_moving_target(vec4 m) {
  float g = DN_PARAM_VALUE(svgf, harm_guard);
  return vec4(m.rgb, m.w >= 0.0 ? g * g * m.w : -1.0);
}
// A still sample's variance at p: the larger of the temporal mean's v times
// its variance divisor and the mean over p's 3x3 still neighbours of their
// own samples' variance. A few samples of sparse light (a caustic, a small
// source) are often all 0, or hold one firefly, and the variance of p's own
// would pull the filtered value onto that mean; the moments' exponential
// average forgets a firefly that the running mean keeps.
float dn_still_sample_variance(vec4 m, float len, float still_n, int s, uint p) {
  float sum = 0.0, count = 0.0;
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  [[dont_unroll]] for (int o = 0; o < 9; ++o) {
    ivec2 q = pos + ivec2(o % 3 - 1, o / 3 - 1);
    if (!dn_inside(q, frame.size.xy)) continue;
    uint iq = uint(q.y) * frame.size.x + uint(q.x);
    float n = s == 0 ? still_mean_at(iq).a : still_mean2_at(iq).a;
    if (!(n >= 2.0)) continue;
    sum += (s == 0 ? still_m2.data[iq] : still_m2_2.data[iq]) / (n - 1.0);
    count += 1.0;
  }
  return max(m.w * dn_svgf_variance_divisor(len, still_n, s == 1 && SPECULAR_ALPHA), sum / max(count, 1.0));
}
// A still pixel (its running mean holds 2 or more samples): the moving
// target's variance is that of a still sample (above) over the samples the
// temporal mean averages, and while its history holds fewer than
// DN_GUARD_SURE_LENGTH samples both targets' a^2 are widened by
// (DN_GUARD_SURE_LENGTH / len)^2: a variance from 4 samples of sparse light
// is mostly 0 (dnrender scene 2, 1 spp: HDR-FLIP rose from 3 to 4 frames
// as the guard switched on, 0.5190 to 0.5674 for svgf; 0.5082 with this).
// Moving pixels keep the guard as it was measured on moving sequences.
const float DN_GUARD_SURE_LENGTH = 8.0;
// Signal s's guard targets at a still pixel: moving's a^2 (as above) and the
// still target, its running mean and a^2, of weight w (0: none).
void dn_still_targets(vec4 own, float len, int s, uint p, inout vec4 moving, out vec4 still, out float w) {
  still = vec4(0.0);
  w = 0.0;
  vec4 mean = DN_CONVERGING_STILL ? (s == 0 ? still_mean_at(p) : still_mean2_at(p)) : vec4(0.0);
  if (!(mean.a >= 2.0)) return;
  float s2 = dn_still_sample_variance(own, len, mean.a, s, p);
  float r = max(1.0, DN_GUARD_SURE_LENGTH / len);
  float widening = r * r;
  float g = DN_PARAM_VALUE(svgf, harm_guard), k = DN_PARAM_VALUE(svgf, converge_still);
  moving.w = g * g * (s2 / dn_svgf_variance_divisor(len, mean.a, s == 1 && SPECULAR_ALPHA)) * widening;
  w = dn_still_weight(mean.a);
  if (w > 0.0) still = vec4(mean.rgb, k * k * s2 / mean.a * widening);
}
// f beyond a (t.w = a^2) from t.rgb in luminance: shrunk toward it by (a / Y(f - t))^1, or ^3 (cubic).
vec3 dn_guarded(vec3 f, vec4 t, bool cubic) {
  vec3 d = f - t.rgb;
  float dl = dn_luminance(d);
  float r = t.w / (dl * dl);
  return dl * dl > t.w ? t.rgb + d * (cubic ? r * sqrt(r) : r) : f;
}
// What a kept pixel blends toward where it is still: its still running
// mean once that holds a sample (then it shows exactly what the plain mean
// of its samples shows), else its temporal mean m. .w negative: no data.
vec4 dn_guard_mean(vec4 m, int s, uint p) {
  if (!(m.w >= 0.0)) return vec4(m.rgb, -1.0);
  if (DN_CONVERGING_STILL) {
    vec4 mean = s == 0 ? still_mean_at(p) : still_mean2_at(p);
    if (mean.a >= 1.0) return vec4(mean.rgb, 1.0);
  }
  return vec4(m.rgb, 1.0);
}
// f guarded toward signal s's targets (own: its temporal mean and variance).
vec3 dn_harm_guard(vec3 f, vec4 own, float len, int s, uint p) {
  if (!HARM_GUARD || DN_PARAM_VALUE(svgf, harm_guard) <= 0.0 || !(own.w >= 0.0) || len < DN_GUARD_MIN_LENGTH) return f;
  vec4 moving_target = dn_moving_target(own), still;
  float w;
  dn_still_targets(own, len, s, p, moving_target, still, w);
  vec3 moving = dn_guarded(f, moving_target, false);
  return w > 0.0 ? mix(moving, dn_guarded(f, still, true), w) : moving;
}

// An unexplained pixel (dn_unexplained) keeps its own current radiance
// (split: diffuse + specular; less emission, added below), or where it is
// still its own unfiltered temporal mean.

vec3 specular_modulator(uint p) {
  return SPECULAR_FACTOR ? dn_guarded_albedo(DN_LOAD3(specular_factor, p)) : vec3(1.0);
}

// The specular radiance sent for p (split sessions with KEEP_UNEXPLAINED).
vec3 raw_specular(uint p) {
  return dn_sanitize_radiance(DN_LOAD3(raw2, p)) * (RAW2_DIVIDED ? specular_modulator(p) : vec3(1.0));
}

// The current radiance of an unexplained pixel, less emission; a: its
// albedo, ga: guarded. Blended toward its means only where the albedo is
// no reflectance (then the demodulated means are radiance, ga 1): one above
// DN_REFLECTANCE_MAX is a frame's own (Cycles' Denoising Albedo of the light
// one reflected sample hit), and the means of other frames' samples, which
// other albedos demodulated, are not radiance times it.
vec3 kept_radiance(uint p, vec3 a, vec3 ga) {
  vec3 c = dn_sanitize_radiance(DN_LOAD3(raw, p)) * (RAW_DIVIDED ? ga : vec3(1.0));
  if (HAS_SPECULAR) {
    c += raw_specular(p);
  } else if (HAS_EMISSION) {
    c = max(c - dn_sanitize_radiance(DN_LOAD3(emission, p)), vec3(0.0));
  }
  if (HARM_GUARD && dn_no_reflectance(a)) {
    vec2 mv = DN_LOAD2(motion, p) * frame.motion.xy;
    vec4 m = dn_guard_mean(own_at(p), 0, p);
    vec4 m2 = HAS_SPECULAR ? dn_guard_mean(own2_at(p), 1, p) : vec4(0.0);
    if (dn_motion_usable(mv) && m.w >= 0.0 && m2.w >= 0.0)
      c = mix(c, m.rgb * ga + (HAS_SPECULAR ? m2.rgb * specular_modulator(p) : vec3(0.0)), dn_stillness(mv));
  }
  return c;
}

// EMISSION_STILL: emission is added back unfiltered, so whatever else a
// renderer puts there (Cycles' transmission and volumes, by --preset cycles
// in split sessions) keeps its one-sample noise; where the pixel is still
// (motion below DN_STILL_MOTION, no reset) its running mean of its own
// emission samples is added instead, so it converges as the plain mean
// does. A change in place (an animated emitter) restarts it: once the mean
// holds DN_EMISSION_MIN_SAMPLES (fewer give no usable variance), the sample's
// luminance beyond DN_EMISSION_T standard deviations of the mean's samples
// (plus 1e-3 of it, for noise-free lights) in two frames in a row (a
// one-sample outlier of noisy light fails once: merged into the mean, not
// into M2, which it would widen past the next test, and marked suspect).
// A sample the sanitizer changed is not counted. Moving pixels: the sample;
// background ones too, keeping no mean: renderers write no motion there
// (Cycles: 0), so a pixel turning from a wall to the sky would look still.
const float DN_EMISSION_T = 6.0;
const float DN_EMISSION_MIN_SAMPLES = 8.0;
vec3 emission_added(uint p) {
  vec3 raw = DN_LOAD3(emission, p);
  vec3 e = dn_sanitize_radiance(raw);
  if (!EMISSION_STILL) return e;
  if (!dn_is_foreground(DN_LOAD1(depth, p))) {
    emission_still.data[p] = vec4(0.0);
    return e;
  }
  vec2 mv = DN_LOAD2(motion, p) * frame.motion.xy;
  vec4 s = vec4(0.0);
  vec2 t = vec2(0.0);  // M2 of the samples' luminance, suspect
  if ((frame.size.w & DN_FLAG_RESET) == 0u && dn_motion_usable(mv) && dn_is_still(mv)) {
    s = emission_still.data[p];
    t = vec2(emission_test.data[2u * p], emission_test.data[2u * p + 1u]);
  }
  if (dn_is_valid_radiance(raw)) {
    float l = dn_luminance(e), lm = dn_luminance(s.rgb);
    bool fail = false;
    if (s.a >= DN_EMISSION_MIN_SAMPLES) {
      float d = l - lm, bound = 1e-3 * max(l, lm);
      fail = d * d > DN_EMISSION_T * DN_EMISSION_T * t.x / (s.a - 1.0) * (1.0 + 1.0 / s.a) + bound * bound;
    }
    if (s.a > 0.0 && !(fail && t.y != 0.0)) {
      float n = min(s.a + 1.0, DN_STILL_MAX_SAMPLES);
      vec3 mean = mix(s.rgb, e, 1.0 / n);
      t = vec2(fail ? t.x : t.x + (l - lm) * (l - dn_luminance(mean)), fail ? 1.0 : 0.0);
      s = vec4(mean, n);
    } else {
      s = vec4(e, 1.0);
      t = vec2(0.0);
    }
  }
  emission_still.data[p] = s;
  emission_test.data[2u * p] = t.x;
  emission_test.data[2u * p + 1u] = t.y;
  return s.a > 0.0 ? s.rgb : e;
}

vec3 remodulate(uint p, out bool kept) {
  vec3 a = DN_LOAD3(albedo, p);
  vec3 ga = dn_guarded_albedo(a);
  // Below one sample per pixel an unsampled pixel has no radiance of its own: the filter's, as every pixel's.
  bool keeping = KEEP_UNEXPLAINED && DN_PARAM_VALUE(svgf, keep_unexplained) != 0.0 &&
                 (!MASKED || dn_is_sampled(DN_LOAD1(sample_count, p)));
  kept = keeping && dn_unexplained(a);
  vec3 c;
  if (kept) {
    c = kept_radiance(p, a, ga);
  } else {
    c = dn_harm_guard(illum_at(p).rgb, HARM_GUARD ? own_at(p) : vec4(-1.0),
                      HARM_GUARD ? colour_history_at(p).a : 0.0, 0, p) * ga;
    if (HAS_SPECULAR && keeping && SPECULAR_FACTOR && dn_no_reflectance(DN_LOAD3(specular_factor, p)))
      c += raw_specular(p);  // no specular lobe: what the filter brought in is the neighbours'
    else if (HAS_SPECULAR)
      c += dn_harm_guard(specular_at(p).rgb, HARM_GUARD ? own2_at(p) : vec4(-1.0),
                         HARM_GUARD ? colour_history2_at(p).a : 0.0, 1, p) * specular_modulator(p);
  }
  if (HAS_EMISSION) c += emission_added(p);
  return c;
}

vec4 taa_history_of(ivec2 q) { return taa_history_at(uint(q.y) * frame.size.x + uint(q.x)); }

// The weight of the current frame in svgf_taa's blend: taa_alpha where the
// pixel moves (1, no blend, when 0), at most taa_static_alpha where it is
// static: nothing moved, so averaging the output over frames only takes out
// the flicker the a-trous leaves (docs/pipelines.md, "svgf in detail", 5).
// A pixel kept as rendered blends only where it is still (its motion, that
// of its surface, is not that of what it shows), and not with a still
// running mean (converge_still), which it then shows as it is. Where the
// still mean is the guard's target (DN_STILL_MIN_SAMPLES or more samples)
// the output converges, and a blend of small weight (progressive's 0.1)
// lags behind it: at least DN_STILL_BLEND_WEIGHT there.
const float DN_STILL_BLEND_WEIGHT = 0.5;
float taa_weight(uint p, vec2 mv, bool kept) {
  if (kept && DN_CONVERGING_STILL) return 1.0;
  float moving = DN_PARAM_VALUE(svgf, taa_alpha) > 0.0 && !kept ? DN_PARAM_VALUE(svgf, taa_alpha) : 1.0;
  float still = DN_PARAM_VALUE(svgf, taa_static_alpha);
  float weight = still <= 0.0 || still >= moving ? moving : mix(moving, still, dn_stillness(mv));
  bool converging = DN_CONVERGING_STILL && still_mean_at(p).a >= DN_STILL_MIN_SAMPLES;
  return converging ? max(weight, DN_STILL_BLEND_WEIGHT) : weight;
}

// DISPLAY_LAG (progressive's display_lag; paper 004 5's buffer one step
// behind): the state s per pixel by which svgf_taa's 3x3 clamp gives way,
// max(s, 0). s = -1 (armed) while the pixel's history holds fewer than
// luminance_min_age samples; 1 at the first frame it holds that many, when its
// history switches source and its filter gains the luminance weight: the
// display then moves to the new filter at the blend's ratio instead of
// snapping into the new 3x3 box; then s shrinks by (1 - weight) a frame.
// Motion ends it (x stillness: the clamp keeps a moving highlight from
// ghosting); 0 without a usable TAA history. prev_s: the previous state at
// the reprojection's heaviest tap.
float display_lag(uint p, bool valid, float weight, vec2 mv, float prev_s) {
  if (colour_history_at(p).a < DN_PARAM_VALUE(atrous, luminance_min_age)) return -1.0;
  if (!valid) return 0.0;
  return (prev_s < 0.0 ? 1.0 : prev_s * (1.0 - weight)) * dn_stillness(mv);
}

// TAA: the previous final output at p + mv, bilinear over the taps inside the
// image (renormalized); none (weight 1) when reset, background, motion not
// finite or the accepted weight < DN_MIN_TAP_WEIGHT (off-screen), and not
// read where the blend weight is 1 anyway (a moving pixel without taa_alpha).
void taa_prepare(uint p, vec3 c, bool kept) {
  uvec2 size = frame.size.xy;
  vec3 prev = vec3(0.0);
  float prev_lag = 0.0;
  bool valid = false;
  vec2 mv = DN_LOAD2(motion, p) * frame.motion.xy;
  float weight = dn_motion_usable(mv) ? taa_weight(p, mv, kept) : 1.0;
  ivec2 origin;
  vec4 weights;
  if (weight < 1.0 && (frame.size.w & DN_FLAG_RESET) == 0u && dn_is_foreground(DN_LOAD1(depth, p)) &&
      dn_bilinear_footprint(dn_previous_position(p, size.x, mv), size, origin, weights)) {
    vec3 s = vec3(0.0);
    float sw = 0.0, heaviest = 0.0;
    ivec2 taps[4] = ivec2[4](origin, origin + ivec2(1, 0), origin + ivec2(0, 1), origin + ivec2(1, 1));
    for (int k = 0; k < 4; ++k) {
      if (!dn_inside(taps[k], size)) continue;
      vec4 h = taa_history_of(taps[k]);
      s += weights[k] * h.rgb;
      sw += weights[k];
      if (DISPLAY_LAG && weights[k] > heaviest) {
        heaviest = weights[k];
        prev_lag = h.a;
      }
    }
    if (sw >= DN_MIN_TAP_WEIGHT) {
      valid = true;
      prev = s / sw;
    }
  }
  float lag = DISPLAY_LAG ? display_lag(p, valid, weight, mv, prev_lag) : 0.0;
  // Negative for a pixel kept as rendered: svgf_taa leaves it out of its neighbours' 3x3 boxes.
  taa_current.data[p] = vec4(c, (valid ? weight : 1.0) * (kept ? -1.0 : 1.0));
  taa_previous.data[p] = vec4(prev, lag);
}

void main() {
  uint pair = dn_invocation_index();
  uint n = frame.size.z;
  uint p0 = 2u * pair;
  if (p0 >= n) return;
  bool has_b = p0 + 1u < n;
  bool kept_a, kept_b = false;
  vec3 a = remodulate(p0, kept_a);
  vec3 b = vec3(0.0);
  if (has_b) b = remodulate(p0 + 1u, kept_b);
  if (TAA) {
    taa_prepare(p0, a, kept_a);
    if (has_b) taa_prepare(p0 + 1u, b, kept_b);
    return;
  }
  if (TO_DISPLAY) {
    display.data[p0] = vec4(a, 0.0);
    if (has_b) display.data[p0 + 1u] = vec4(b, 0.0);
  } else {
    DN_STORE_RGB_PAIR(result, pair, a, b, has_b)
  }
}
