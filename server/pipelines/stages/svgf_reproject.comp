#version 450
// svgf_reproject: sanitize, demodulate, luminance moments, history clipping
// (CLIP) and temporal integration of colour and moments (docs/pipelines.md,
// "svgf in detail", 1).
// One invocation per pixel.
//
// Resources: svgf_reproject.pass (binding 0 FrameConstants); the
// buffer layouts are described there.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "reproject.glsl"
#include "luminance.glsl"
#include "pass.glsl"
#include "generated/passes/svgf_reproject.pass"

#include "svgf.glsl"
#include "svgf_signal.glsl"
#include "clip.glsl"
#include "reflect.glsl"

// MASKED: whether pixel q has a sample this frame (sanitize.glsl's rule).
bool sampled(uint q) { return dn_is_sampled(DN_LOAD1(sample_count, q)); }

// An unsampled background pixel's fill sources: the background pixels
// sampled this frame (background keeps no history).
bool dn_fill_source(ivec2 q, out vec3 value) {
  uint qi = uint(q.y) * frame.size.x + uint(q.x);
  value = dn_svgf_current(qi);
  return sampled(qi) && !dn_is_foreground(dn_svgf_depth(qi));
}
#include "ring_fill.glsl"

// History clipping (CLIP): the box a history is clipped to. Paper 001's
// box, the per-channel min/max of the prefiltered current signal
// (svgf_clip_prefilter) over the 5x5 foreground pixels around p, narrowed to
// the raw 3x3 range of the current signal where the two overlap (the raw
// range where they do not: a small highlight's blur widens the first beyond
// the highlight's surroundings and cuts its peak), then widened to p's own
// current value d and by `widen` on both sides. False when no pixel of the
// 5x5 window is foreground (then nothing is clipped). The raw neighbours
// come from svgf_clip_prefilter's current signal (dn_svgf_current's values,
// one texel fetch each), as do history_rejected's.
bool clip_box(ivec2 pos, vec3 d, float widen, bool needed, out vec3 lo, out vec3 hi) {
  vec3 pre_lo = vec3(1e38), pre_hi = vec3(-1e38), raw_lo = d, raw_hi = d;
  bool any = false;
  // Loops of no iterations where the box is not needed, not ifs: llvmpipe
  // runs an if's body whatever its condition, and a loop's once, masked
  // (svgf_variance.comp). min and max do not depend on the order.
  int window = needed ? 25 : 0;
  [[dont_unroll]] for (int o = 0; o < window; ++o) {
    ivec2 q = pos + ivec2(o % 5 - 2, o / 5 - 2);
    if (!dn_inside(q, frame.size.xy)) continue;
    vec4 v = neighbourhood_at(uint(q.y) * frame.size.x + uint(q.x));
    if (v.w != 0.0) {
      pre_lo = min(pre_lo, v.rgb);
      pre_hi = max(pre_hi, v.rgb);
      any = true;
    }
  }
  int raw = needed ? 9 : 0;
  [[dont_unroll]] for (int o = 0; o < raw; ++o) {
    ivec2 q = pos + ivec2(o % 3 - 1, o / 3 - 1);
    if (o == 4 || !dn_inside(q, frame.size.xy)) continue;
    vec3 dq = current_at(uint(q.y) * frame.size.x + uint(q.x)).rgb;
    raw_lo = min(raw_lo, dq);
    raw_hi = max(raw_hi, dq);
  }
  vec3 nlo = max(pre_lo, raw_lo), nhi = min(pre_hi, raw_hi);
  bvec3 overlap = lessThanEqual(nlo, nhi);
  lo = min(mix(raw_lo, nlo, overlap), d) - vec3(widen);
  hi = max(mix(raw_hi, nhi, overlap), d) + vec3(widen);
  return any;
}

// The history's sample noise at p for the rejection test and the static
// clip: the standard deviation from the luminance moments, the largest over
// the 3x3 history pixels around p's previous position `prev` (with history)
// and p's own reprojected moments. One pixel's moments average about five
// frames, and at 1 spp a penumbra or sparse indirect light often shows five
// alike in a row: its own sigma then says "quiet" and the next sample
// contradicts it (still-camera temporal error 1.3-2x, docs/results.md).
// Read only where `needed` (a loop of no iterations elsewhere: clip_box).
float history_sigma(ivec2 prev, vec2 own, bool needed) {
  float sigma = dn_moments_sigma(own);
  int taps = needed ? 9 : 0;
  [[dont_unroll]] for (int o = 0; o < taps; ++o) {
    ivec2 q = prev + ivec2(o % 3 - 1, o / 3 - 1);
    if (!dn_inside(q, frame.size.xy)) continue;
    uvec4 bits = prev_aux_at(uint(q.y) * frame.size.x + uint(q.x));
    if (uintBitsToFloat(bits.z) > 0.0) sigma = max(sigma, dn_moments_sigma(uintBitsToFloat(bits.xy)));
  }
  return sigma;
}

// History rejection (clip.glsl): the history is contradicted by the
// prefiltered current luminance lp, by p's own current luminance l and, on
// the same side, by at least DN_REJECT_NEIGHBOURS of the 8 raw current
// neighbours. A highlight that arrived or left covers its neighbours too; a
// sparse bright sample (1-spp indirect light) does not, and rejecting on it
// made the history of every such pixel restart over and over (still-camera
// temporal error 2-8x, docs/results.md).
// Tested only where `tested` (a loop of no iterations elsewhere: clip_box).
bool history_rejected(ivec2 pos, float l, float lp, float lh, float sigma, bool tested) {
  bool test = tested && dn_history_contradicted(lp, lh, sigma) && dn_history_contradicted(l, lh, sigma);
  int agree = 0;
  int neighbours = test ? 9 : 0;
  [[dont_unroll]] for (int o = 0; o < neighbours; ++o) {
    ivec2 q = pos + ivec2(o % 3 - 1, o / 3 - 1);
    if (o == 4 || !dn_inside(q, frame.size.xy)) continue;
    float lq = dn_luminance(current_at(uint(q.y) * frame.size.x + uint(q.x)).rgb);
    if ((lq > lh) == (l > lh) && dn_history_contradicted(lq, lh, sigma)) ++agree;
  }
  return test && agree >= DN_REJECT_NEIGHBOURS;
}

// Whether p's history is clipped: sanitized roughness below clip_roughness
// (a non-finite one counts as rough, 1: not clipped).
bool clipped_here(uint p) {
  return CLIP && dn_sanitize_roughness(DN_LOAD1(roughness, p)) < DN_PARAM_VALUE(svgf, clip_roughness);
}

// Whether the history's depth and normal tests apply at this pixel (off at
// REFLECTION's glossy pixels); set by main before the taps are read.
bool geometry_tests = true;

// Falcor's consistency test of a previous pixel q (the previous pixel must
// have left history: stored depth > 0).
bool tap_valid(ivec2 q, float z, vec3 n, vec2 grad, out vec4 aux) {
  aux = vec4(0.0);
  if (!dn_inside(q, frame.size.xy)) return false;
  uvec4 bits = prev_aux_at(uint(q.y) * frame.size.x + uint(q.x));
  aux = vec4(uintBitsToFloat(bits.xyz), 0.0);
  if (!(aux.z > 0.0)) return false;
  if (!geometry_tests) return true;
  return dn_same_surface(z, n, grad, aux.z, dn_svgf_unpack_normal(bits.w));
}

void add_tap(ivec2 q, float w, float z, vec3 n, vec2 grad, inout vec3 sc, inout vec2 sm, inout float sl,
             inout float sw) {
  vec4 aux;
  if (!tap_valid(q, z, n, grad, aux)) return;
  vec4 h = prev_colour_at(uint(q.y) * frame.size.x + uint(q.x));
  sc += w * h.rgb;
  sl += w * h.a;
  sm += w * aux.xy;
  sw += w;
}

// CONVERGE_STILL: p's running mean of its own samples d (and the M2 of their
// luminance) goes on where p's surface keeps its history and p is still (continues),
// else it restarts from d; a pixel without a sample this frame keeps it while
// it continues, else has none. Returns the mean as stored (.a: samples).
vec4 update_still_mean(uint p, vec3 d, bool has_sample, bool continues) {
  if (!CONVERGE_STILL) return vec4(0.0);
  vec4 prev = still_mean.data[p];
  if (!has_sample) {
    if (!continues) {
      still_mean.data[p] = vec4(0.0);
      still_m2.data[p] = 0.0;
      return vec4(0.0);
    }
    return prev;
  }
  float n = continues && prev.a > 0.0 ? min(prev.a + 1.0, DN_STILL_MAX_SAMPLES) : 1.0;
  vec3 mean = n == 1.0 ? d : mix(prev.rgb, d, 1.0 / n);
  float l = dn_luminance(d);
  // At the cap the mean is an exponential average: M2 decays with it.
  float m2 = n == prev.a ? still_m2.data[p] * (1.0 - 1.0 / n) : still_m2.data[p];
  still_m2.data[p] = n == 1.0 ? 0.0 : m2 + (l - dn_luminance(prev.rgb)) * (l - dn_luminance(mean));
  still_mean.data[p] = vec4(mean, n);
  return vec4(mean, n);
}

// A change in a still view (a shadow falls, a light is switched): b, the
// luminance of the current samples over p's 3x3 foreground pixels averaged
// without the largest and the smallest, keeps beside p's still mean its
// running mean and M2, its recent mean r (an exponential average of weight
// DN_CHANGE_ALPHA) and the same average of b's variance as the box's spread
// shows it (still_change). From DN_CHANGE_MIN_SAMPLES on, r beyond t standard
// deviations of itself from the running mean (plus 1e-3 of it) restarts
// p's still mean and history; the variance is the larger of the M2's (of
// the samples before b: a changed light's would widen the test that is to
// catch it) and the spread's (the first bright samples of sparse light,
// which the M2 has not seen yet). t: 3 darker, 4 brighter (1-spp light is
// skewed to the bright side). One pixel's 1-spp noise hides the change of
// its own light for many frames, nine pixels' over a few frames much less
// often. Not below one sample per pixel (MASKED): the box's samples change
// with the mask.
const float DN_CHANGE_T_DARKER = 3.0, DN_CHANGE_T_BRIGHTER = 4.0;
const float DN_CHANGE_ALPHA = 0.25;
const float DN_CHANGE_MIN_SAMPLES = 8.0;
// vec2(b, b's variance from the spread of the box's values).
vec2 box_luminance(ivec2 pos) {
  float sum = 0.0, sum2 = 0.0, count = 0.0, lo = 1e38, hi = 0.0;
  [[dont_unroll]] for (int o = 0; o < 9; ++o) {
    ivec2 q = pos + ivec2(o % 3 - 1, o / 3 - 1);
    if (!dn_inside(q, frame.size.xy)) continue;
    uint qi = uint(q.y) * frame.size.x + uint(q.x);
    if (!dn_is_foreground(dn_svgf_depth(qi))) continue;
    float l = dn_luminance(CLIP ? current_at(qi).rgb : dn_svgf_current(qi));
    sum += l;
    sum2 += l * l;
    count += 1.0;
    lo = min(lo, l);
    hi = max(hi, l);
  }
  if (count < 3.0) return vec2(sum / count, 0.0);
  float spread = max(sum2 - sum * sum / count, 0.0) / (count - 1.0);
  return vec2((sum - lo - hi) / (count - 2.0), spread / (count - 2.0));
}
// Whether p's still mean goes on (it continues and its light has not changed).
bool still_unchanged(uint p, ivec2 pos, bool continues) {
  if (!CONVERGE_STILL || MASKED) return continues;
  vec2 box = box_luminance(pos);
  float b = box.x;
  vec4 s = still_change.data[p];  // running mean, M2, recent mean, recent spread variance
  float n = still_mean.data[p].a;
  if (!continues || !(n > 0.0)) {
    still_change.data[p] = vec4(b, 0.0, b, box.y);
    return false;
  }
  float k = min(n + 1.0, DN_STILL_MAX_SAMPLES);
  float a = max(1.0 / k, DN_CHANGE_ALPHA);
  vec2 recent = mix(s.zw, box, a);
  // The recent mean's variance about the running mean: v (a / (2 - a) + 1 / n).
  float dev = recent.x - s.x, bound = 1e-3 * max(recent.x, s.x);
  float t = dev < 0.0 ? DN_CHANGE_T_DARKER : DN_CHANGE_T_BRIGHTER;
  float v = max(n > 1.0 ? s.y / (n - 1.0) : 0.0, recent.y);
  if (n >= DN_CHANGE_MIN_SAMPLES && dev * dev > t * t * v * (a / (2.0 - a) + 1.0 / n) + bound * bound) {
    still_change.data[p] = vec4(b, 0.0, b, box.y);
    return false;
  }
  float mean = mix(s.x, b, 1.0 / k);
  float m2 = (k == n ? s.y * (1.0 - 1.0 / k) : s.y) + (b - s.x) * (b - mean);
  still_change.data[p] = vec4(mean, m2, recent);
  return true;
}

// The temporal colour (.w: its variance divisor, dn_svgf_variance_divisor)
// and moments of p. A still pixel whose running mean holds more than
// DN_STILL_FILTER_FROM samples, or more than its history (after a rejection
// the mean went through): the filter starts from that plain mean, its
// length is their count and its moments theirs (the exponential moments
// forget a firefly the mean still holds, and the filter let go of it), so
// its variance and the a-trous's luminance edge-stopping fall (faster than
// 1 / n) and the filter lets go as the mean converges. The history is an
// exponential blend of the filtered colour (feedback_tap): it keeps the
// filter's blur.
void write_temporal(uint p, vec3 colour, vec2 moments, float len, vec4 still) {
  float still_n = 0.0;
  if (DN_CONVERGING_STILL && still.a > min(len, DN_STILL_FILTER_FROM)) {
    colour = still.rgb;
    len = still_n = still.a;
    float l = dn_luminance(still.rgb);
    moments = vec2(l, l * l + still_m2.data[p] / max(still.a - 1.0, 1.0));
  }
  illum.data[p] = vec4(colour, dn_svgf_variance_divisor(len, still_n, SPECULAR_ALPHA));
  temporal.data[p] = vec4(moments, len, dn_luminance(colour));
}

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  uvec2 size = frame.size.xy;
  ivec2 pos = ivec2(p % size.x, p / size.x);

  vec3 d = dn_svgf_current(p);
  float l = dn_luminance(d);
  vec2 m = vec2(l, l * l);
  float z = dn_svgf_depth(p);
  if (!dn_is_foreground(z)) {
    // Background is passed through; below one sample per pixel an unsampled
    // one shows its nearest sampled background neighbours (else it is 0).
    vec3 fill;
    if (MASKED && !sampled(p) && dn_ring_fill(pos, size, fill)) {
      d = fill;
      l = dn_luminance(d);
      m = vec2(l, l * l);
    }
    illum.data[p] = vec4(d, 1.0);
    if (WRITE_GUIDE) guide.data[p] = uvec4(0u);
    temporal.data[p] = vec4(m, 0.0, l);
    update_still_mean(p, d, false, false);
    return;
  }
  vec3 n = dn_svgf_normal(p);
  bool has_normal = dot(n, n) > 0.0;
  vec2 grad = dn_svgf_gradients(pos, z, n);
  vec2 mv = DN_LOAD2(motion, p) * frame.motion.xy;
  // Whether p is still: its surface's motion, but at a mirror the
  // reflection's (its modulator holds the reflected albedo, which a moving
  // reflection changes). A still glossy pixel's representative-ray match
  // follows each sample's reflected hit, which moves without any change.
  vec2 still_mv = mv;
  bool history_allowed = READ_HISTORY;
  if (REFLECTION) {
    vec4 r = reflection_at(p);
    mv = r.xy;
    geometry_tests = r.z != DN_REFLECT_GLOSSY;
    if (geometry_tests) still_mv = mv;
    history_allowed = history_allowed && r.w != DN_REFLECT_REJECTED;  // reflect's Eq. 1 threshold
  }
  const bool reads_history = history_allowed && (frame.size.w & DN_FLAG_RESET) == 0u;

  vec3 prev = vec3(0.0);
  vec2 prev_m = vec2(0.0);
  float prev_len = 0.0;
  bool valid = false;
  ivec2 origin;
  vec4 weights;
  if (reads_history && has_normal && dn_motion_usable(mv) &&
      dn_bilinear_footprint(dn_previous_position(p, size.x, mv), size, origin, weights)) {
    vec3 sc = vec3(0.0);
    vec2 sm = vec2(0.0);
    float sl = 0.0, sw = 0.0;
    add_tap(origin, weights.x, z, n, grad, sc, sm, sl, sw);
    add_tap(origin + ivec2(1, 0), weights.y, z, n, grad, sc, sm, sl, sw);
    add_tap(origin + ivec2(0, 1), weights.z, z, n, grad, sc, sm, sl, sw);
    add_tap(origin + ivec2(1, 1), weights.w, z, n, grad, sc, sm, sl, sw);
    // Falcor's fallback: equal weights over the valid taps of the 3x3 box
    // around the pixel that contains p_prev. Not with MASKED: there most
    // pixels without history simply had no sample yet, and taking their
    // neighbours' would fill them from neighbours (paper 004 §5: missing
    // values are never overwritten from neighbours). A loop of no taps
    // elsewhere, not an if: llvmpipe runs an if's body whatever its
    // condition, and a loop's once masked (svgf_variance.comp).
    bool fallback = sw < DN_MIN_TAP_WEIGHT && !MASKED;
    if (fallback) {
      sc = vec3(0.0);
      sm = vec2(0.0);
      sl = 0.0;
      sw = 0.0;
    }
    ivec2 centre = ivec2(floor(dn_previous_position(p, size.x, mv)));
    int box_taps = fallback ? 9 : 0;
    [[dont_unroll]] for (int o = 0; o < box_taps; ++o)
      add_tap(centre + ivec2(o % 3 - 1, o / 3 - 1), 1.0, z, n, grad, sc, sm, sl, sw);
    if (sw > 0.0) {
      valid = true;
      prev = sc / sw;
      prev_m = sm / sw;
      prev_len = floor(sl / sw + 0.5);  // integral lengths: no fp32 vs exact flips of the len < 4 test
    }
  }
  // The still mean follows the geometry, not the clip's rejection: a sparse
  // 1-spp highlight contradicts its history often, and its own change test
  // (still_unchanged) catches a change of light.
  bool surface_kept = valid;
  // Clipped signals (highlights and reflections): reject a history the
  // current frame contradicts, else clip it to the current neighbourhood.
  if (CLIP) {
    bool clip = valid && clipped_here(p);
    vec4 pre = neighbourhood_at(p);
    ivec2 prev_pixel = ivec2(floor(dn_previous_position(p, size.x, mv)));
    // Not with REFLECTION: that history follows the reflection, and the
    // thesis clips it without rejecting (scene 6 glossy temporal error
    // 0.00379 with rejection, 0.00310 without; RMSE within 0.1 %).
    // p's own sigma first: the 3x3 one is never smaller, so a history p's
    // own moments do not contradict is kept without reading the other eight.
    float own = dn_moments_sigma(prev_m), lp = dn_luminance(pre.rgb), lh = dn_luminance(prev);
    bool test = clip && !REFLECTION && pre.w > 0.0 && dn_history_contradicted(lp, lh, own) &&
                dn_history_contradicted(l, lh, own);
    // A static pixel's surface and its reflections have not moved, so its
    // history is clipped only beyond its noise: the 1-spp box misses the mean
    // of sparse or two-valued light often (still-camera temporal error
    // 1.1-2.3x without this, docs/results.md); a change of the light itself
    // beyond the noise is still clipped or rejected.
    float still = dn_stillness(mv);
    float sigma = history_sigma(prev_pixel, prev_m, test || (clip && still > 0.0));
    if (history_rejected(pos, l, lp, lh, sigma, test)) valid = false;
    vec3 lo, hi;
    bool boxed = clip_box(pos, d, still > 0.0 ? still * sigma : 0.0, clip && valid, lo, hi);
    if (clip && valid && boxed) {
      vec3 clipped = dn_clip_to_box(prev, lo, hi);
      // A clipped history's luminance moments restart from its clipped
      // colour: the old ones still hold the light the clip removed.
      if (clipped != prev) {
        float lc = dn_luminance(clipped);
        prev_m = vec2(lc, lc * lc);
      }
      prev = clipped;
    }
  }
  if (WRITE_GUIDE)
    guide.data[p] = uvec4(floatBitsToUint(has_normal ? z : -z), has_normal ? dn_svgf_pack_normal(n) : 0u,
                          floatBitsToUint(grad.x), REFLECTION ? uint(reflection_at(p).z) : 0u);
  // The still mean is p's own: it goes on only where p's own previous pixel
  // is its surface (a valid history may come from Falcor's 3x3 fallback).
  // SURFACE_STILL: p's surface is the pixel's, whose still mean the first
  // chain kept (2 or more samples) or restarted this frame; the reflected
  // hit's guides and Eq. 1 follow each sample's reflected hit, which at a
  // still pixel differs from frame to frame without any change.
  // A sample without a normal (a renderer's guide left empty, as Cycles'
  // Denoising Normal on some paths) is one more of the same pixel: across
  // it p's own depth alone decides, and its still mean goes on.
  vec4 own_aux;
  float own_z = CONVERGE_STILL ? uintBitsToFloat(prev_aux_at(p).z) : 0.0;  // negative: it had no normal
  bool depth_only = !has_normal || own_z < 0.0;
  bool own_kept = depth_only ? reads_history && own_z != 0.0 && dn_same_depth(z, grad.x, abs(own_z))
                             : surface_kept && tap_valid(pos, z, n, grad, own_aux);
  bool continues = CONVERGE_STILL && dn_is_still(still_mv) && (SURFACE_STILL ? surface_still.data[p].a >= 2.0 : own_kept);
  bool has_sample = dn_is_valid_radiance(DN_LOAD3(signal, p));
  if (has_sample && !still_unchanged(p, pos, continues) && continues) {
    continues = false;
    valid = false;
  }
  // MASKED and no sample here this frame (a NaN count is none): the history
  // as reprojected, or no data (length 0) without one.
  if (MASKED && !sampled(p)) {
    write_temporal(p, prev, prev_m, valid ? prev_len : 0.0, update_still_mean(p, d, false, continues));
    return;
  }
  // A sample the sanitizer changed is none for the still mean: it would stay in it.
  vec4 still = update_still_mean(p, d, has_sample, continues);
  float len = valid ? min(prev_len + 1.0, DN_PARAM_VALUE(svgf, max_history)) : 1.0;
  float alpha = valid ? max(1.0 / len, DN_SVGF_ALPHA_COLOUR) : 1.0;
  float alpha_m = valid ? max(1.0 / len, DN_PARAM_VALUE(svgf, alpha_moments)) : 1.0;
  vec3 colour = mix(prev, d, alpha);
  vec2 moments = mix(prev_m, m, alpha_m);
  write_temporal(p, colour, moments, len, still);
}
