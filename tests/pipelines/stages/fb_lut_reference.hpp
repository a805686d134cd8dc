// Independent CPU reference of the F_beta BRDF pre-integration (paper 000,
// Eq. 7) in double precision, written from the definition in
// docs/pipelines.md ("F_β LUT"), not from the shader:
//
//   F_beta(w_o) = ∫ f_r(w_o, w_i) cos θ_i dw_i = F0·A + B,
//   f_r = D(h) G2(v, l) F(v·h) / (4 (n·v)(n·l)),
//   A = ∫ (f_r/F)(1 − (1 − v·h)^5) cos θ_i dw_i,  B = ∫ (f_r/F)(1 − v·h)^5 cos θ_i dw_i,
//
// isotropic GGX D with GGX α (= protocol roughness), height-correlated Smith
// G2 = 1 / (1 + Λ(v) + Λ(l)), Λ(x) = (−1 + sqrt(1 + α² tan²θ_x)) / 2, Schlick F.
//
// The shader importance-samples 1024 Hammersley half-vectors; this reference
// evaluates f_r·cos directly with nested adaptive Gauss–Kronrod (7/15-point)
// quadrature, so the two estimate the same integral by different means:
//  - LightSpace: over the light hemisphere in (θ_i, φ_i), breakpoints at the
//    mirror direction (θ_i = θ_o, φ_i = π); used for α ≥ kFbHalfVectorBelow;
//  - HalfVectorSpace: over the half-vector hemisphere in (θ_h, φ_h) with the
//    Jacobian dw_i = 4 (v·h) dw_h and breakpoints at θ_h = atan(k·α), which
//    resolves the narrow lobe of small α; used for α < kFbHalfVectorBelow.
// Both use the mirror symmetry φ → −φ (integrate φ over [0, π], double).
// Target accuracy ~1e-6 absolute (tests cross-check the two methods).
#pragma once

namespace dn::test {

inline constexpr double kFbHalfVectorBelow = 0.05;  // α below which the half-vector quadrature is used

enum class FbQuadrature { Auto, LightSpace, HalfVectorSpace };

struct FbAB {
  double a = 0;  // scale of F0
  double b = 0;  // bias
};

// (A, B) at cos θ_o in (0, 1] and GGX α in (0, 1].
FbAB fb_reference(double cos_o, double alpha, FbQuadrature method = FbQuadrature::Auto);

// White-furnace directional albedo, ∫ D G2 / (4 cos θ_o) dw_i (F = 1), as a
// separate integral (its own quadrature run, no Fresnel split).
double fb_directional_albedo(double cos_o, double alpha, FbQuadrature method = FbQuadrature::Auto);

}  // namespace dn::test
