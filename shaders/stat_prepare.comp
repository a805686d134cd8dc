#version 450
// stat_prepare: the per-pixel inputs of the Welch test (paper 003 Alg. 2;
// docs/pipelines.md, "stat"), per RGB channel of the sample statistics:
//   s2    = M2 / (n - 1)                       Bessel-corrected sample variance
//   var   = max(M2 / (n (n - 1)), variance_floor)   variance of the mean
//   theta = mean + (M3 / n) / (6 s2 n)   if s2 > FLT_EPSILON, else mean
//           (skew correction of the Box-Cox mean, Johnson 1978)
// A pixel without statistics, n < 2 (one sample has no variance), or any
// non-finite statistic, gets n = 0 in theta.w: it is no one's neighbour and
// keeps its own raw mean. One invocation per pixel.
//
// Resources: passes/stat_prepare.pass (binding 0 FrameConstants).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "sanitize.glsl"
#include "pass.glsl"
#include "passes/stat_prepare.pass"

const float FLT_EPSILON = 1.1920929e-7;

void main() {
  uint p = dn_invocation_index();
  if (p >= frame.size.z) return;
  float n = count.data[p];
  vec3 mu = vec3(mean.data[3u * p], mean.data[3u * p + 1u], mean.data[3u * p + 2u]);
  vec3 sum2 = vec3(m2.data[3u * p], m2.data[3u * p + 1u], m2.data[3u * p + 2u]);
  vec3 sum3 = vec3(m3.data[3u * p], m3.data[3u * p + 1u], m3.data[3u * p + 2u]);
  bool usable = dn_is_finite(n) && n >= 2.0 && dn_is_finite(mu) && dn_is_finite(sum2) && dn_is_finite(sum3);
  if (!usable) {
    theta.data[p] = vec4(0.0);
    variance.data[p] = vec4(0.0);
    return;
  }
  vec3 s2 = max(sum2, 0.0) / (n - 1.0);
  vec3 var = max(s2 / n, vec3(DN_PARAM_VALUE(stat, variance_floor)));
  vec3 skew = (sum3 / n) / (6.0 * s2 * n);
  vec3 t = mix(mu, mu + skew, greaterThan(s2, vec3(FLT_EPSILON)));
  theta.data[p] = vec4(t, n);
  variance.data[p] = vec4(var, 0.0);
}
