#version 450
// fb_lut: the F_beta table (BRDF pre-integration, paper 000 Eq. 7/8;
// docs/pipelines.md, "F_β LUT"), computed once per device
// (server/pipelines/stages/fb_lut.cpp). One invocation per texel (i, j):
// cos θ_o = (i + 0.5) / N, GGX α = (j + 0.5) / N (fb_lut.glsl), output
// vec2 (A, B) at j · N + i with F_beta = F0 · A + B for isotropic GGX,
// height-correlated Smith G2 and Schlick F = F0 + (1 − F0)(1 − v·h)^5:
//   A = ∫ (f_r / F)(1 − (1 − v·h)^5) cos θ_i dw_i,  B = ∫ (f_r / F)(1 − v·h)^5 cos θ_i dw_i.
//
// Estimator: SAMPLES importance samples per texel on the Hammersley points
// (ξ1, ξ2) = ((k + 0.5) / SAMPLES, radical inverse of k); the half-vector is
// drawn from GGX's distribution of visible normals (Heitz 2018,
// D_v(h) = G1(v) max(0, v·h) D(h) / (n·v)), l = 2 (v·h) h − v, so
// pdf_l = G1(v) D / (4 n·v) and each sample weighs
//   f_r cos θ_i / pdf_l = F · G2(v, l) / G1(v).
// With S_x = sqrt(cos²θ_x (1 − α²) + α²): Λ(x) = (S_x / cos θ_x − 1) / 2,
//   G1(v) = 2 (n·v) / ((n·v) + S_v),  G2 = 2 (n·v)(n·l) / ((n·l) S_v + (n·v) S_l),
//   G2 / G1 = (n·l)((n·v) + S_v) / ((n·l) S_v + (n·v) S_l)  ∈ [0, 1]
// (S_l ≥ n·l): no division by n·v, finite as n·v → 0 and α → 0 (the
// denominator ≥ α (n·l + n·v) > 0, and is still clamped to ≥ 1e-30). Samples
// with n·l ≤ 0 or v·h ≤ 0 add 0. No sample weighs more than 1 (clamped, so
// fp32 rounding cannot push one above), and the sum E = Σ w is accumulated
// as such (B = Σ w (1 − v·h)^5, A = E − B): rounding to nearest is monotonic,
// so every partial sum stays ≤ its sample count and E / SAMPLES ≤ 1 exactly;
// A + B then exceeds 1 by at most the rounding of that last add (~1e-7).
// (Sampling D(h)(n·h) instead, weight G2 (v·h) / ((n·h)(n·v)), was measured
// at errors up to 1.3e-2 with 1024 samples near grazing; this one stays below
// 1.3e-3: docs/pipelines.md.)
//
// Resources: fb_lut.pass (no constants block: binding 0 of the layout is unused).
#extension GL_GOOGLE_include_directive : require
#define DN_FB_LUT_NO_LOOKUP
#include "fb_lut.glsl"
#include "pass.glsl"

layout(local_size_x_id = 0, local_size_y = 1, local_size_z = 1) in;
#include "generated/passes/fb_lut.pass"

const float PI = 3.14159265358979;

void main() {
  const uint n = uint(DN_FB_LUT_SIZE);
  uint t = gl_GlobalInvocationID.x;
  if (t >= n * n) return;
  float nv = dn_fb_lut_axis(t % n);
  float alpha = dn_fb_lut_axis(t / n);
  float a2 = alpha * alpha;
  vec3 v = vec3(sqrt(max(1.0 - nv * nv, 0.0)), 0.0, nv);  // azimuth 0
  float sv = sqrt(nv * nv * (1.0 - a2) + a2);

  // Visible-normal sampling frame in the stretched (α = 1) configuration.
  // v has no y component, so T1 = (0, 1, 0) is Heitz's (−Vh.y, Vh.x, 0) / |.|
  // (and a valid choice when Vh = n) and T2 = cross(Vh, T1) = (−Vh.z, 0, Vh.x).
  vec3 vh_dir = normalize(vec3(alpha * v.x, 0.0, v.z));
  vec3 t1_dir = vec3(0.0, 1.0, 0.0);
  vec3 t2_dir = vec3(-vh_dir.z, 0.0, vh_dir.x);
  float s = 0.5 * (1.0 + vh_dir.z);

  float sum_e = 0.0;  // Σ w      (F0 = 1: A + B)
  float sum_b = 0.0;  // Σ w (1 − v·h)^5
  for (uint k = 0u; k < SAMPLES; ++k) {
    float xi1 = (float(k) + 0.5) / float(SAMPLES);
    float xi2 = float(bitfieldReverse(k)) * 2.3283064365386963e-10;  // radical inverse, < 1
    float r = sqrt(xi1);
    float phi = 2.0 * PI * xi2;
    float p1 = r * cos(phi);
    float p2 = mix(sqrt(max(1.0 - p1 * p1, 0.0)), r * sin(phi), s);
    vec3 nh = p1 * t1_dir + p2 * t2_dir + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh_dir;
    vec3 h = normalize(vec3(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
    float vh = dot(v, h);
    float nl = 2.0 * vh * h.z - nv;  // (2 (v·h) h − v)·n
    if (vh <= 0.0 || nl <= 0.0) continue;
    float sl = sqrt(nl * nl * (1.0 - a2) + a2);
    float w = min(nl * (nv + sv) / max(nl * sv + nv * sl, 1e-30), 1.0);  // G2 / G1(v) ≤ 1
    float fc = 1.0 - vh;
    float fc2 = fc * fc;
    float schlick = fc2 * fc2 * fc;  // (1 − v·h)^5
    sum_e += w;
    sum_b += w * schlick;
  }
  float e = sum_e / float(SAMPLES);
  float b = sum_b / float(SAMPLES);
  table.data[t] = vec2(max(e - b, 0.0), b);
}
