#version 450
// reflect_median (reflect, last pass): paper 001 §6's firefly suppression,
// a 3x3 median of the displayed frame at foreground pixels whose 3x3
// foreground window is all of reflection class none (a diffuse or rough
// surface away from mirror and glossy pixels, whose highlights and edges a
// median would cut): per channel, the median of the window's filtered light
// (colour minus emission; the value of rank count / 2), plus the pixel's own
// emission (a small light is not a firefly), where the pixel's light is
// brighter than that median (in luminance); a darker pixel keeps its own: a
// firefly is bright, and the median of the dark detail around a rough
// surface's shadows and edges cost scene 2 SSIM 0.322 -> 0.287. Per channel, not the
// luminance-ranked vector median: that one jumps to another pixel's colour
// when two luminances swap order, so fp rounding upstream changed the output
// by up to 0.6 % (scene 6, scale test), where a scalar median moves only as
// much as its inputs. Neighbours that emit are left out of the window: a
// light is another surface, and beside it the lit surface (dnrender scene
// 3's lamp) is no firefly against the light's reflected light, about 0.
// It reads the chain's displayed frame and writes only Output: no history
// is touched.
// A full window (9 pixels, nearly every one) takes the median-of-9 exchange
// network (Paeth, Graphics Gems; 19 component-wise min/max pairs on all three
// channels at once), a partial one the rank count / 2 search; both pick the
// same value. The windows are unrolled so that nothing is indexed at run
// time (on lavapipe a dynamically indexed array lives in memory: the rank
// search over every window cost 14 ms at 320x180).
// docs/pipelines.md "reflect".
// One invocation per pixel pair.
//
// Resources: reflect_median.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "frame.glsl"
#include "plane.glsl"
#include "sanitize.glsl"
#include "luminance.glsl"
#include "reproject.glsl"
#include "pass.glsl"
#include "generated/passes/reflect_median.pass"

#include "svgf_guards.glsl"
#include "reflect.glsl"

vec3 emitted(uint p) { return HAS_EMISSION ? dn_sanitize_radiance(DN_LOAD3(emission, p)) : vec3(0.0); }

// One exchange of the network: a gets the component-wise min, b the max.
#define DN_EXCHANGE(a, b) \
  {                        \
    vec3 lo_ = min(a, b);  \
    b = max(a, b);         \
    a = lo_;               \
  }

// The per-channel median of nine values (their rank-4 value).
vec3 median_of_9(vec3 v[9]) {
  DN_EXCHANGE(v[1], v[2]) DN_EXCHANGE(v[4], v[5]) DN_EXCHANGE(v[7], v[8])
  DN_EXCHANGE(v[0], v[1]) DN_EXCHANGE(v[3], v[4]) DN_EXCHANGE(v[6], v[7])
  DN_EXCHANGE(v[1], v[2]) DN_EXCHANGE(v[4], v[5]) DN_EXCHANGE(v[7], v[8])
  DN_EXCHANGE(v[0], v[3]) DN_EXCHANGE(v[5], v[8]) DN_EXCHANGE(v[4], v[7])
  DN_EXCHANGE(v[3], v[6]) DN_EXCHANGE(v[1], v[4]) DN_EXCHANGE(v[2], v[5])
  DN_EXCHANGE(v[4], v[7]) DN_EXCHANGE(v[4], v[2]) DN_EXCHANGE(v[6], v[4])
  DN_EXCHANGE(v[4], v[2])
  return v[4];
}

// The per-channel median of the light (colour minus emission) of p's 3x3
// window, emitting neighbours left out; false where the window is not all of
// class none (no median applies).
bool window_median(uint p, out vec3 median) {
  ivec2 pos = ivec2(p % frame.size.x, p / frame.size.x);
  vec3 colours[9];
  bool taken[9];
  int count = 0;
  median = vec3(0.0);
  [[unroll]] for (int k = 0; k < 9; ++k) {
    ivec2 q = pos + ivec2(k % 3 - 1, k / 3 - 1);
    uint qi = uint(q.y) * frame.size.x + uint(q.x);
    taken[k] = dn_inside(q, frame.size.xy) && dn_is_foreground(DN_LOAD1(depth, qi));
    colours[k] = vec3(0.0);
    if (taken[k]) {
      if (features.data[2u * qi].w != DN_REFLECT_NONE) return false;
      vec3 e = emitted(qi);
      taken[k] = k == 4 || !(dn_luminance(e) > 0.0);
      colours[k] = src_at(qi).rgb - e;
      count += taken[k] ? 1 : 0;
    }
  }
  if (count == 9) {
    median = median_of_9(colours);
    return true;
  }
  // Per channel, the value with as many smaller as larger ones (rank count / 2).
  int want = count / 2;
  [[unroll]] for (int i = 0; i < 9; ++i) {
    ivec3 below = ivec3(0);
    [[unroll]] for (int j = 0; j < 9; ++j) {
      bvec3 smaller = lessThan(colours[j], colours[i]);
      bvec3 tie_before = j < i ? equal(colours[j], colours[i]) : bvec3(false);
      below += taken[j] ? ivec3(smaller) + ivec3(tie_before) : ivec3(0);
    }
    if (taken[i]) median = mix(median, colours[i], equal(below, ivec3(want)));
  }
  return true;
}

// A still pixel keeps its own value against the median, by its running
// mean's weight (dn_still_weight), where that mean of n samples is
// significantly brighter than the median: their relative difference beyond
// DN_MEDIAN_T standard errors of the mean, relative to it. A bright line one
// pixel thin beside a light passes once its samples agree; a firefly's mean
// never does (its standard error is about its own excess over the median).
const float DN_MEDIAN_T = 3.0;
vec3 filtered(uint p) {
  vec3 c = src_at(p).rgb;
  if (features.data[2u * p].w != DN_REFLECT_NONE || !dn_is_foreground(DN_LOAD1(depth, p))) return c;
  vec3 median;
  if (!window_median(p, median)) return c;
  vec3 e = emitted(p);
  vec3 own = c - e;
  float y = dn_luminance(own), y_median = dn_luminance(median);
  if (!(y > y_median)) return own + e;
  vec3 m = median + e;
  if (!CONVERGE_STILL) return m;
  vec4 mean = still_mean_at(p);
  float w = dn_still_weight(mean.a);
  if (!(w > 0.0)) return m;
  float ym = dn_luminance(mean.rgb);
  float margin = (y - y_median) / y;
  float se2 = still_m2.data[p] / ((mean.a - 1.0) * mean.a) / (ym * ym);
  return margin * margin > DN_MEDIAN_T * DN_MEDIAN_T * se2 ? mix(m, c, w) : m;
}

void main() {
  uint pair = dn_invocation_index();
  uint p0 = 2u * pair;
  if (p0 >= frame.size.z) return;
  bool has_b = p0 + 1u < frame.size.z;
  vec3 a = filtered(p0);
  vec3 b = has_b ? filtered(p0 + 1u) : vec3(0.0);
  DN_STORE_RGB_PAIR(result, pair, a, b, has_b)
}
