#include "fb_lut_reference.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <queue>
#include <vector>

namespace dn::test {
namespace {

using Pair = std::array<double, 2>;
constexpr double kPi = std::numbers::pi;

// Gauss–Kronrod 7/15 on [-1, 1]: Kronrod nodes (the odd ones are the Gauss
// nodes), Kronrod and Gauss weights.
constexpr double kXgk[8] = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                            0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                            0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                            0.207784955007898467600689403773245, 0.0};
constexpr double kWgk[8] = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                            0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                            0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                            0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
constexpr double kWg[4] = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                           0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

struct Piece {
  double lo, hi;
  Pair value;
  double error;
  bool operator<(const Piece& o) const { return error < o.error; }  // max-heap on the error
};

template <class F>
Piece gauss_kronrod(const F& f, double lo, double hi) {
  const double c = 0.5 * (lo + hi), r = 0.5 * (hi - lo);
  Pair k{0, 0}, g{0, 0};
  const Pair centre = f(c);
  for (int d = 0; d < 2; ++d) {
    k[d] = kWgk[7] * centre[d];
    g[d] = kWg[3] * centre[d];
  }
  for (int i = 0; i < 7; ++i) {
    const Pair a = f(c - r * kXgk[i]), b = f(c + r * kXgk[i]);
    for (int d = 0; d < 2; ++d) {
      k[d] += kWgk[i] * (a[d] + b[d]);
      if (i % 2 == 1) g[d] += kWg[i / 2] * (a[d] + b[d]);
    }
  }
  Piece p{lo, hi, {k[0] * r, k[1] * r}, 0};
  p.error = std::max(std::abs((k[0] - g[0]) * r), std::abs((k[1] - g[1]) * r));
  return p;
}

// Globally adaptive: bisects the piece with the largest error estimate until
// the summed estimate is below max(abs_tol, rel_tol·|value|) or max_pieces.
template <class F>
Pair integrate(const F& f, const std::vector<double>& breaks, double abs_tol, double rel_tol, int max_pieces) {
  std::priority_queue<Piece> pieces;
  for (size_t i = 0; i + 1 < breaks.size(); ++i)
    if (breaks[i + 1] > breaks[i]) pieces.push(gauss_kronrod(f, breaks[i], breaks[i + 1]));
  Pair value{0, 0};
  double error = 0;
  auto totals = [&] {
    value = {0, 0};
    error = 0;
    auto copy = pieces;
    while (!copy.empty()) {
      value[0] += copy.top().value[0];
      value[1] += copy.top().value[1];
      error += copy.top().error;
      copy.pop();
    }
  };
  totals();
  while (static_cast<int>(pieces.size()) < max_pieces &&
         error > std::max(abs_tol, rel_tol * std::max(std::abs(value[0]), std::abs(value[1])))) {
    const Piece worst = pieces.top();
    pieces.pop();
    const double mid = 0.5 * (worst.lo + worst.hi);
    const Piece left = gauss_kronrod(f, worst.lo, mid), right = gauss_kronrod(f, mid, worst.hi);
    for (int d = 0; d < 2; ++d) value[d] += left.value[d] + right.value[d] - worst.value[d];
    error += left.error + right.error - worst.error;
    pieces.push(left);
    pieces.push(right);
  }
  totals();  // re-sum to shed the rounding of the running updates
  return value;
}

std::vector<double> sorted_breaks(std::vector<double> b, double lo, double hi) {
  for (double& x : b) x = std::clamp(x, lo, hi);
  b.push_back(lo);
  b.push_back(hi);
  std::sort(b.begin(), b.end());
  b.erase(std::unique(b.begin(), b.end()), b.end());
  return b;
}

// The BRDF's pieces, straight from the definitions.
struct Brdf {
  double alpha, nv, sin_o;
  bool split;  // true: (A, B) with Schlick's (1 − v·h)^5; false: (F = 1, 0)

  // GGX D from the half-vector's sin²θ_h and cos²θ_h (no 1 − cos² cancellation).
  double ggx_d(double sin2_h, double cos2_h) const {
    const double a2 = alpha * alpha;
    const double t = sin2_h + a2 * cos2_h;  // = 1 + (α² − 1) cos²θ_h
    return a2 / (kPi * t * t);
  }
  double smith_lambda(double cos_x) const {
    const double tan2 = (1.0 - cos_x * cos_x) / (cos_x * cos_x);
    return (-1.0 + std::sqrt(1.0 + alpha * alpha * tan2)) / 2.0;
  }
  double g2(double nl) const { return 1.0 / (1.0 + smith_lambda(nv) + smith_lambda(nl)); }
  Pair fresnel_split(double vh, double value) const {
    if (!split) return {value, 0.0};
    const double s = std::pow(1.0 - vh, 5.0);
    return {value * (1.0 - s), value * s};
  }

  // f_r·cos θ_i per unit solid angle of l, times sin θ_i (the (θ_i, φ) measure).
  Pair light_space(double theta, double phi) const {
    const double st = std::sin(theta), ct = std::cos(theta);
    const double l[3] = {st * std::cos(phi), st * std::sin(phi), ct};
    const double v[3] = {sin_o, 0.0, nv};
    double hv[3] = {v[0] + l[0], v[1] + l[1], v[2] + l[2]};
    const double len = std::sqrt(hv[0] * hv[0] + hv[1] * hv[1] + hv[2] * hv[2]);
    if (!(len > 0) || !(ct > 0)) return {0, 0};
    for (double& x : hv) x /= len;
    const double vh = v[0] * hv[0] + v[1] * hv[1] + v[2] * hv[2];
    const double d = ggx_d(hv[0] * hv[0] + hv[1] * hv[1], hv[2] * hv[2]);
    // f_r cos θ_i = D G2 F / (4 (n·v)(n·l)) · (n·l)
    return fresnel_split(vh, d * g2(ct) / (4.0 * nv) * st);
  }

  // The same integrand over half-vectors: dw_i = 4 (v·h) dw_h, times sin θ_h.
  Pair half_vector_space(double theta_h, double phi_h) const {
    const double st = std::sin(theta_h), ct = std::cos(theta_h);
    const double h[3] = {st * std::cos(phi_h), st * std::sin(phi_h), ct};
    const double vh = sin_o * h[0] + nv * h[2];
    if (!(vh > 0)) return {0, 0};
    const double nl = 2.0 * vh * h[2] - nv;  // l = 2 (v·h) h − v
    if (!(nl > 0)) return {0, 0};
    const double d = ggx_d(st * st, ct * ct);
    return fresnel_split(vh, d * g2(nl) / (4.0 * nv) * 4.0 * vh * st);
  }
};

constexpr double kInnerAbs = 1e-10, kInnerRel = 1e-9, kOuterAbs = 1e-8, kOuterRel = 1e-8;
constexpr int kMaxPieces = 400;

Pair integrate_brdf(double cos_o, double alpha, FbQuadrature method, bool split) {
  const Brdf brdf{alpha, cos_o, std::sqrt(std::max(0.0, 1.0 - cos_o * cos_o)), split};
  if (method == FbQuadrature::Auto)
    method = alpha < kFbHalfVectorBelow ? FbQuadrature::HalfVectorSpace : FbQuadrature::LightSpace;
  const double half_pi = kPi / 2;
  Pair half{0, 0};
  if (method == FbQuadrature::LightSpace) {
    // Lobe around the mirror direction (θ_o, φ = π).
    const double theta_o = std::acos(cos_o);
    const auto outer_breaks = sorted_breaks(
        {theta_o - 8 * alpha, theta_o - 2 * alpha, theta_o, theta_o + 2 * alpha, theta_o + 8 * alpha}, 0, half_pi);
    const auto inner_breaks = sorted_breaks({kPi - 8 * alpha, kPi - 2 * alpha}, 0, kPi);
    half = integrate(
        [&](double theta) {
          return integrate([&](double phi) { return brdf.light_space(theta, phi); }, inner_breaks, kInnerAbs,
                           kInnerRel, kMaxPieces);
        },
        outer_breaks, kOuterAbs, kOuterRel, kMaxPieces);
  } else {
    const auto outer_breaks = sorted_breaks({std::atan(alpha), std::atan(4 * alpha), std::atan(16 * alpha),
                                             std::atan(64 * alpha)},
                                            0, half_pi);
    const std::vector<double> inner_breaks = {0, kPi / 2, kPi};
    half = integrate(
        [&](double theta_h) {
          return integrate([&](double phi_h) { return brdf.half_vector_space(theta_h, phi_h); }, inner_breaks,
                           kInnerAbs, kInnerRel, kMaxPieces);
        },
        outer_breaks, kOuterAbs, kOuterRel, kMaxPieces);
  }
  return {2 * half[0], 2 * half[1]};  // φ ∈ [0, π] covers half the hemisphere
}

}  // namespace

FbAB fb_reference(double cos_o, double alpha, FbQuadrature method) {
  const Pair p = integrate_brdf(cos_o, alpha, method, true);
  return {p[0], p[1]};
}

double fb_directional_albedo(double cos_o, double alpha, FbQuadrature method) {
  return integrate_brdf(cos_o, alpha, method, false)[0];
}

}  // namespace dn::test
