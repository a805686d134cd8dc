// Student's t quantiles from the inverse regularised incomplete beta function
// (paper 003 Alg. 2; ../shared/papers/IMPLEMENTATION-NOTES.md A.2 P1).
//
// The upper tail of t with ν degrees of freedom is Q(t) = ½ I_x(ν/2, ½) with
// x = ν/(ν + t²), so t = sqrt(ν (1 − x)/x). Both x and y = 1 − x are carried
// exactly: for small ν the solution x is tiny, for large ν (ν = 1e6: x ≈ 1 −
// 1e-5) it is y, and recovering the small one as 1 − (the other) would lose
// digits. The solver therefore always works on the variable that is ≤ ½.
#include "pipelines/stat/student_t.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>

namespace dn::pipelines {
namespace {

[[noreturn]] void bad_argument(const char* function, const char* name, const char* range, double value) {
  char text[160];
  std::snprintf(text, sizeof text, "%s: %s must be %s, got %.17g", function, name, range, value);
  throw std::invalid_argument(text);
}

bool positive_finite(double v) { return v > 0.0 && std::isfinite(v); }

// ln Γ(z) − [(z − ½) ln z − z + ½ ln 2π], the Stirling series; its truncation
// error is below 1e-16 for z ≥ 15.
double stirling_tail(double z) {
  const double r = 1.0 / z, r2 = r * r;
  return r * (1.0 / 12 - r2 * (1.0 / 360 - r2 * (1.0 / 1260 - r2 * (1.0 / 1680 - r2 / 1188))));
}

// ln B(a, b). lgamma(a) + lgamma(b) − lgamma(a + b) cancels badly for large
// arguments (ν = 1e6: lgamma(5e5) ≈ 6e6, an absolute error of 1e-9 that the
// tail probability would inherit), so large arguments use Stirling's form
// with the cancellation done analytically.
double log_beta(double a, double b) {
  const double small = std::min(a, b), big = std::max(a, b), sum = a + b;
  if (big < 15.0) return std::lgamma(a) + std::lgamma(b) - std::lgamma(sum);
  const double corr = stirling_tail(big) - stirling_tail(sum);
  // lgamma(big) − lgamma(sum), with (big − ½) ln(big/sum) written as log1p.
  const double ratio_term = -(big - 0.5) * std::log1p(small / big);
  if (small < 15.0) return std::lgamma(small) + ratio_term - small * std::log(sum) + small + corr;
  return 0.5 * std::log(2.0 * std::numbers::pi) + (small - 0.5) * std::log(small / sum) - 0.5 * std::log(sum) + ratio_term +
         stirling_tail(small) + corr;
}

// The continued fraction of I_x(a, b) (modified Lentz), which converges fast
// for x < (a + 1)/(a + b + 2); it needs O(sqrt(max(a, b))) terms.
double beta_continued_fraction(double x, double a, double b) {
  constexpr double kTiny = 1e-300;
  constexpr double kEps = 4 * DBL_EPSILON;
  constexpr int kMaxTerms = 1000000;
  const double qab = a + b, qap = a + 1.0, qam = a - 1.0;
  double c = 1.0, d = 1.0 - qab * x / qap;
  if (std::fabs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int k = 1; k <= kMaxTerms; ++k) {
    const double m = k, m2 = 2.0 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));  // even step
    d = 1.0 + aa * d;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));  // odd step
    d = 1.0 + aa * d;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::fabs(delta - 1.0) <= kEps) return h;
  }
  throw std::runtime_error("incomplete_beta: continued fraction did not converge");
}

// ln of the lower tail I_x(a, b) (upper = false) or of the upper tail
// 1 − I_x(a, b), with y = 1 − x given exactly by the caller. The fraction is
// evaluated on the side where it converges; the tail it yields is accurate to
// a few ulp relative, the other one is 1 minus it (≥ about ½ there).
double log_tail(double x, double y, double a, double b, bool upper) {
  if (x <= 0.0) return upper ? 0.0 : -INFINITY;
  if (y <= 0.0) return upper ? -INFINITY : 0.0;
  // Take each logarithm from the exact one of x, y: with a = 5e5, ln x from a
  // rounded x = 1 − y would put an error of 5e-11 into ln tail.
  const double log_x = x <= 0.5 ? std::log(x) : std::log1p(-y);
  const double log_y = y <= 0.5 ? std::log(y) : std::log1p(-x);
  const double log_front = a * log_x + b * log_y - log_beta(a, b);
  const bool lower_side = x < (a + 1.0) / (a + b + 2.0);
  const double log_cf_tail = lower_side ? log_front + std::log(beta_continued_fraction(x, a, b) / a)
                                        : log_front + std::log(beta_continued_fraction(y, b, a) / b);
  if (lower_side != upper) return log_cf_tail;
  return std::log1p(-std::exp(log_cf_tail));
}

// The v in (0, ½] with tail(v) = target, tail being I_v(a, b) or 1 − I_v(a, b);
// the caller has checked that the solution is at most ½. Newton on ln tail
// against u = ln v: near 0 the tails are power laws in v, so that iteration is
// almost linear, and for large ν (Gaussian-like tails) it is concave and
// converges monotonically. A bracket with bisection in u keeps every step safe.
double solve_tail(double target, double a, double b, bool upper) {
  const double lbeta = log_beta(a, b), log_target = std::log(target);
  double lo = std::log(DBL_MIN), hi = std::log(0.5);
  // Start from the small-v law I_v(a, b) ≈ v^a / (a B(a, b)).
  double u = (std::log(upper ? 1.0 - target : target) + std::log(a) + lbeta) / a;
  u = std::isnan(u) ? hi : std::clamp(u, lo, hi);
  double step_old = hi - lo, step_older = step_old;
  for (int iteration = 0; iteration < 400; ++iteration) {
    const double v = std::exp(u);
    const double h = log_tail(v, 1.0 - v, a, b, upper) - log_target;
    if (h == 0.0) return v;
    if ((h < 0.0) != upper) lo = u;  // the lower tail grows with v, the upper one shrinks
    else hi = u;
    // d ln tail / d ln v = ± v · density(v) / tail(v).
    const double slope = (upper ? -1.0 : 1.0) *
                         std::exp(a * u + (b - 1.0) * std::log1p(-v) - lbeta - (h + log_target));
    double next = u - h / slope;
    // Bisect when Newton leaves the bracket or stops halving the step (rtsafe's rule).
    if (!(next > lo && next < hi) || std::fabs(next - u) > 0.5 * std::fabs(step_older)) next = 0.5 * (lo + hi);
    step_older = step_old;
    step_old = next - u;
    const bool converged = std::fabs(next - u) <= 2 * DBL_EPSILON * std::max(1.0, std::fabs(u));
    u = next;
    if (converged || hi - lo <= 2 * DBL_EPSILON * std::max(1.0, std::fabs(u))) return std::exp(u);
  }
  throw std::runtime_error("inverse_incomplete_beta: no convergence");
}

// t with upper tail probability q in (0, ½] (so t ≥ 0). The table passes α/2
// here directly: 1 − α/2 would round the tail before it is inverted.
double quantile_from_upper_tail(double q, double nu) {
  if (q == 0.5) return 0.0;
  const double target = 2.0 * q, a = 0.5 * nu;
  double x, y;  // x = ν/(ν + t²), y = 1 − x
  if (target <= std::exp(log_tail(0.5, 0.5, a, 0.5, false))) {
    x = solve_tail(target, a, 0.5, false);  // I_x(ν/2, ½) = 2q, small x: small ν or far tails
    y = 1.0 - x;
  } else {
    y = solve_tail(target, 0.5, a, true);  // 1 − I_y(½, ν/2) = 2q, small y: large ν
    x = 1.0 - y;
  }
  return std::sqrt(nu) * std::sqrt(y / x);
}

}  // namespace

double incomplete_beta(double x, double a, double b) {
  if (!(x >= 0.0 && x <= 1.0)) bad_argument("incomplete_beta", "x", "in [0, 1]", x);
  if (!positive_finite(a)) bad_argument("incomplete_beta", "a", "positive and finite", a);
  if (!positive_finite(b)) bad_argument("incomplete_beta", "b", "positive and finite", b);
  return std::exp(log_tail(x, 1.0 - x, a, b, false));
}

double inverse_incomplete_beta(double p, double a, double b) {
  if (!(p >= 0.0 && p <= 1.0)) bad_argument("inverse_incomplete_beta", "p", "in [0, 1]", p);
  if (!positive_finite(a)) bad_argument("inverse_incomplete_beta", "a", "positive and finite", a);
  if (!positive_finite(b)) bad_argument("inverse_incomplete_beta", "b", "positive and finite", b);
  if (p == 0.0 || p == 1.0) return p;
  if (p <= std::exp(log_tail(0.5, 0.5, a, b, false))) return solve_tail(p, a, b, false);
  // x > ½: solve for y = 1 − x, whose upper tail 1 − I_y(b, a) is I_x(a, b).
  return 1.0 - solve_tail(p, b, a, true);
}

double student_t_quantile(double p, double nu) {
  if (!(p > 0.0 && p < 1.0)) bad_argument("student_t_quantile", "p", "in (0, 1)", p);
  if (!positive_finite(nu)) bad_argument("student_t_quantile", "nu", "positive and finite", nu);
  // 1 − p is exact for p ≥ ½ (Sterbenz), so the tail is never rounded.
  return p < 0.5 ? -quantile_from_upper_tail(p, nu) : quantile_from_upper_tail(1.0 - p, nu);
}

std::vector<float> student_t_table(double alpha, int entries) {
  if (!(alpha > 0.0 && alpha < 1.0)) bad_argument("student_t_table", "alpha", "in (0, 1)", alpha);
  if (entries < 1) bad_argument("student_t_table", "entries", ">= 1", entries);
  std::vector<float> table(static_cast<size_t>(entries));
  // Two-sided test: the critical value leaves α/2 in the upper tail.
  for (int k = 0; k < entries; ++k) table[size_t(k)] = float(quantile_from_upper_tail(0.5 * alpha, k + 1.0));
  return table;
}

}  // namespace dn::pipelines
