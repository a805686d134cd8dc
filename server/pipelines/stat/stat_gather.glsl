// The per-tap decisions of stat's disc gather (docs/pipelines.md, "stat"),
// shared by stat_filter and the tiling benchmark (bench_stat_gather): the
// Welch membership (weight) of tap q in p's disc and q's base weight. The includer
// defines `float dn_stat_t_squared(uint nu, bool still)`, the table entry for
// nu >= 1 at alpha, or at still_alpha for two still pixels with statistics.
#ifndef DN_STAT_GATHER_GLSL
#define DN_STAT_GATHER_GLSL

float dn_stat_t_squared(uint nu, bool still);

struct DnStatKernel {
  float ks, ka, kn;  // -1 / (2 sigma^2) of the spatial, albedo and normal terms
  bool membership;   // false: every tap with statistics is a member (the base filter)
  bool asymmetric;   // Eq. 14 instead of the symmetric test
  float falloff;     // exponent of the membership weight (0: all or nothing, the paper's)
};

#ifdef DN_FRAME_GLSL
// The kernel of the session's stat parameters (passes with FrameConstants).
DnStatKernel dn_stat_kernel_from_parameters() {
  return DnStatKernel(-0.5 / (DN_PARAM_VALUE(stat, sigma_spatial) * DN_PARAM_VALUE(stat, sigma_spatial)),
                      -0.5 / (DN_PARAM_VALUE(stat, sigma_albedo) * DN_PARAM_VALUE(stat, sigma_albedo)),
                      -0.5 / (DN_PARAM_VALUE(stat, sigma_normal) * DN_PARAM_VALUE(stat, sigma_normal)),
                      DN_PARAM_VALUE(stat, membership) != 0.0, DN_PARAM_VALUE(stat, asymmetric) != 0.0,
                      DN_PARAM_VALUE(stat, membership_falloff));
}

// With spatial_shrink_from N > 0, the kernel of a still pixel p holding n > N
// samples of its own (class DN_STAT_TESTED, theta_p.w = n): sigma_spatial
// sqrt(N / n), gathering within 3 of those sigmas (r at most); as n grows it
// narrows to p itself, whose mean is consistent.
void dn_stat_narrow_still(inout DnStatKernel k, inout int r, vec4 theta_p, float pixel_class) {
  float n0 = DN_PARAM_VALUE(stat, spatial_shrink_from);
  if (!(n0 > 0.0) || pixel_class != DN_STAT_TESTED || !(theta_p.w > n0)) return;
  float sigma = DN_PARAM_VALUE(stat, sigma_spatial) * sqrt(n0 / theta_p.w);
  k.ks = -0.5 / (sigma * sigma);
  r = min(r, int(ceil(3.0 * sigma)));
}
#endif

// symmetric:  (theta_p - theta_q)^2 <= t^2 (var_p + var_q)
// asymmetric: (theta_p - theta_q)^2 <  var_p (1 + 2 t^2) - var_q, by the
//             inequality (never through a NaN); equal means with zero
//             variances are members
bool dn_stat_member(vec3 d2, float t2, vec3 var_p, vec3 var_q, bool asymmetric) {
  if (asymmetric) {
    bvec3 pass_ = lessThan(d2, var_p * (1.0 + 2.0 * t2) - var_q);
    bvec3 tie = equal(d2 + var_p + var_q, vec3(0.0));  // equal means, no variance: w* = 0/0, accepted
    return all(bvec3(pass_.x || tie.x, pass_.y || tie.y, pass_.z || tie.z));
  }
  return all(lessThanEqual(d2, t2 * (var_p + var_q)));
}

// The membership weight of q (theta_q = vec4(theta, n), var_q) in p's
// disc: 0 unless q is a member, else (1 - r)^falloff, r the largest
// channel's share of the test's bound, d^2 / (t^2 (var_p + var_q)) or
// d^2 / (var_p (1 + 2 t^2) - var_q) (1 with falloff 0: the paper's
// all-or-nothing membership). q must have statistics (n >= 2); a p without
// variance (n_p < 2) takes q's sample variance as its own, var_q n_q / n_p,
// with nu = n_q - 1. still: p and q are still pixels whose statistics are
// their own (DN_STAT_TESTED); with n_p >= 2 the pair is tested at still_alpha.
float dn_stat_membership(vec4 theta_p, vec3 var_p, vec4 theta_q, vec3 var_q, DnStatKernel k, bool still) {
  if (theta_q.w < 2.0) return 0.0;
  if (!k.membership) return 1.0;
  bool single = theta_p.w < 2.0;
  vec3 d = theta_p.rgb - theta_q.rgb;
  vec3 d2 = d * d;
  // nu >= 1; pairs of pixels with statistics: n_p + n_q - 2 >= 2
  uint nu = single ? max(uint(theta_q.w + 0.5), 2u) - 1u : uint(theta_p.w + theta_q.w + 0.5) - 2u;
  vec3 var_pq = single ? var_q * (theta_q.w / theta_p.w) : var_p;
  float t2 = dn_stat_t_squared(nu, still && !single);
  if (!dn_stat_member(d2, t2, var_pq, var_q, k.asymmetric)) return 0.0;
  if (k.falloff == 0.0) return 1.0;
  // A member's bound exceeds its d^2 > 0; d^2 = 0 (equal means) has r = 0.
  vec3 bound = k.asymmetric ? var_pq * (1.0 + 2.0 * t2) - var_q : t2 * (var_pq + var_q);
  vec3 r = vec3(d2.x > 0.0 ? d2.x / bound.x : 0.0, d2.y > 0.0 ? d2.y / bound.y : 0.0, d2.z > 0.0 ? d2.z / bound.z : 0.0);
  return pow(1.0 - min(max(r.x, max(r.y, r.z)), 1.0), k.falloff);
}

// The base weight of a member at squared pixel distance d2xy with albedo and
// normal differences da, dn (Eq. 16, the authors' standard deviations).
float dn_stat_base_weight(int d2xy, vec3 da, vec3 dn, DnStatKernel k) {
  return exp(k.ks * float(d2xy) + k.ka * dot(da, da) + k.kn * dot(dn, dn));
}

#endif
