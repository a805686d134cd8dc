// The stat pipeline's Student-t table (paper 003 Alg. 2) against independent
// expectations (../shared/papers/IMPLEMENTATION-NOTES.md A.2 P1, A.4 oracle 3):
// the paper's LUT spot values, the closed forms for ν = 1 and ν = 2, the
// Cornish-Fisher expansion around the normal quantile for large ν, closed
// forms of the incomplete beta function and a round trip through its inverse.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "pipelines/stat/student_t.hpp"

namespace dn::pipelines {
namespace {

constexpr double kPi = std::numbers::pi;

double rel_error(double got, double want) { return std::fabs(got - want) / std::fabs(want); }

// Probabilities that reach the far tails the notes ask for (1 − 1e-6).
const std::vector<double> kProbabilities = {1e-6, 1e-4, 0.0025, 0.01, 0.1, 0.3,  0.45,
                                            0.55, 0.7,  0.9,    0.99, 0.9975, 0.9999, 1 - 1e-6};

// The normal quantile by bisection on erfc, independent of the code under test.
double normal_quantile(double p) {
  double lo = -40.0, hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(StudentT, TableMatchesPaperSpotValues) {
  // Notes A.2 P1 (the reference code's LUT for α = 0.005, 4 decimals); index k holds ν = k + 1.
  const struct { int nu; double t; } spots[] = {
      {1, 127.3213}, {2, 14.0890},  {3, 7.4533},   {4, 5.5976},   {6, 4.3168},   {8, 3.8325},   {14, 3.3257},
      {30, 3.0298},  {62, 2.9110},  {126, 2.8573}, {254, 2.8318}, {510, 2.8193}, {1022, 2.8131}};
  const std::vector<float> table = student_t_table(0.005);
  ASSERT_EQ(table.size(), 1024u);
  double max_error = 0.0;
  for (const auto& s : spots) {
    EXPECT_NEAR(table[size_t(s.nu - 1)], s.t, 1e-4) << "nu " << s.nu;
    max_error = std::max(max_error, std::fabs(table[size_t(s.nu - 1)] - s.t));
  }
  RecordProperty("max_abs_error_vs_spot_values", std::to_string(max_error));
}

TEST(StudentT, TableIndexIsTwoNMinusThree) {
  // n samples per side: ν = 2n − 2 at index 2n − 3 (paper 003 Alg. 2's lookup).
  const double alpha = 0.005;
  const std::vector<float> table = student_t_table(alpha);
  for (int n = 2; n <= 513; ++n)
    EXPECT_EQ(table[size_t(2 * n - 3)], float(student_t_quantile(1.0 - alpha / 2, 2.0 * n - 2))) << "n " << n;
  // Shorter tables are prefixes of the long one.
  const std::vector<float> short_table = student_t_table(alpha, 7);
  ASSERT_EQ(short_table.size(), 7u);
  for (size_t k = 0; k < short_table.size(); ++k) EXPECT_EQ(short_table[k], table[k]);
}

TEST(StudentT, OneDegreeOfFreedomAcrossAlphas) {
  // ν = 1 is Cauchy: t_{1−α/2} = tan(π(½ − α/2)) = cot(πα/2).
  EXPECT_NEAR(student_t_table(0.05, 1)[0], 12.706, 5e-4);  // notes A.2 P1, 3 decimals
  for (double alpha : {1e-4, 0.002, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.9})
    EXPECT_NEAR(student_t_table(alpha, 1)[0], 1.0 / std::tan(kPi * alpha / 2), 1e-7 / std::tan(kPi * alpha / 2))
        << "alpha " << alpha;
}

TEST(StudentT, OneDegreeOfFreedomIsCauchy) {
  // tan(π(p − ½)) = −cot(πp) = cot(π(1 − p)); the cot forms stay well
  // conditioned near p = 0 and 1, where tan(π(p − ½)) is not.
  for (double p : kProbabilities) {
    const double want = p < 0.5 ? -1.0 / std::tan(kPi * p) : 1.0 / std::tan(kPi * (1.0 - p));
    EXPECT_LE(rel_error(student_t_quantile(p, 1.0), want), 1e-9) << "p " << p;
  }
  EXPECT_EQ(student_t_quantile(0.5, 1.0), 0.0);
}

TEST(StudentT, TwoDegreesOfFreedomClosedForm) {
  // ν = 2: F(t) = ½ + t / (2 sqrt(2 + t²)). With s = 2p − 1: s² (2 + t²) = t²,
  // t² = 2s² / (1 − s²), and 1 − s² = 4p(1 − p): t = (2p − 1) / sqrt(2p(1 − p)).
  for (double p : kProbabilities) {
    const double want = (2.0 * p - 1.0) / std::sqrt(2.0 * p * (1.0 - p));
    EXPECT_LE(rel_error(student_t_quantile(p, 2.0), want), 1e-9) << "p " << p;
  }
}

TEST(StudentT, LargeNuApproachesNormal) {
  const double z = normal_quantile(0.9975);
  EXPECT_NEAR(z, 2.8070, 1e-4);  // z_0.9975 (StatER's varcizvalue 2.80703)
  EXPECT_NEAR(student_t_quantile(0.9975, 1e6), 2.8070, 1e-3);
  // Cornish-Fisher expansion of t in 1/ν (Abramowitz & Stegun 26.7.5); the
  // omitted 1/ν⁴ term is below 2e-13 relative for ν ≥ 1e4 and |z| ≤ 4.8.
  for (double nu : {1e4, 1e5, 1e6}) {
    for (double p : kProbabilities) {
      const double x = normal_quantile(p), x2 = x * x;
      const double g1 = x * (x2 + 1) / 4;
      const double g2 = x * ((5 * x2 + 16) * x2 + 3) / 96;
      const double g3 = x * (((3 * x2 + 19) * x2 + 17) * x2 - 15) / 384;
      const double want = x + g1 / nu + g2 / (nu * nu) + g3 / (nu * nu * nu);
      EXPECT_LE(rel_error(student_t_quantile(p, nu), want), 1e-9) << "nu " << nu << " p " << p;
    }
  }
}

TEST(StudentT, DecreasesWithDegreesOfFreedom) {
  const std::vector<float> table = student_t_table(0.005);
  for (size_t k = 1; k < table.size(); ++k) EXPECT_LT(table[k], table[k - 1]) << "index " << k;
  const double z = normal_quantile(0.9975);
  double previous = std::numeric_limits<double>::infinity();
  for (double nu = 0.5; nu <= 1e6; nu *= 1.25) {
    const double t = student_t_quantile(0.9975, nu);
    EXPECT_LT(t, previous) << "nu " << nu;
    EXPECT_GT(t, z) << "nu " << nu;  // heavier tails than the normal for every finite ν
    previous = t;
  }
}

TEST(StudentT, IncompleteBetaClosedForms) {
  // I_x(a, 1) = x^a, I_x(1, b) = 1 − (1 − x)^b, I_x(½, ½) = (2/π) asin(sqrt x).
  for (double x : {1e-12, 1e-5, 0.01, 0.2, 0.5, 0.8, 0.99, 1 - 1e-9}) {
    for (double a : {0.3, 1.0, 2.5, 17.0, 300.0}) {
      if (std::pow(x, a) > 1e-300) {  // not underflowed
        EXPECT_LE(rel_error(incomplete_beta(x, a, 1.0), std::pow(x, a)), 1e-12) << "x " << x << " a " << a;
      }
      EXPECT_LE(rel_error(incomplete_beta(x, 1.0, a), -std::expm1(a * std::log1p(-x))), 1e-12)
          << "x " << x << " b " << a;
    }
    // asin(sqrt x) is ill-conditioned near x = 1: use π/2 − asin(sqrt(1 − x)) there.
    const double arcsine = x <= 0.5 ? 2.0 / kPi * std::asin(std::sqrt(x)) : 1.0 - 2.0 / kPi * std::asin(std::sqrt(1.0 - x));
    EXPECT_LE(rel_error(incomplete_beta(x, 0.5, 0.5), arcsine), 1e-12) << "x " << x;
  }
  EXPECT_EQ(incomplete_beta(0.0, 2.0, 3.0), 0.0);
  EXPECT_EQ(incomplete_beta(1.0, 2.0, 3.0), 1.0);
}

TEST(StudentT, InverseIncompleteBetaRoundTrip) {
  // The shapes of the t table (ν/2, ½) and general ones, over nine decades of p.
  const double shapes[][2] = {{0.5, 0.5}, {0.5, 1.0}, {1.0, 0.5}, {2.5, 7.0}, {7.0, 2.5}, {10.0, 10.0},
                              {0.5, 32.0}, {32.0, 0.5}, {64.0, 64.0}, {0.5, 512.0}, {512.0, 0.5}};
  for (const auto& s : shapes) {
    for (double p : {1e-10, 1e-6, 1e-3, 0.005, 0.1, 0.5, 0.9, 0.999, 1 - 1e-6}) {
      const double x = inverse_incomplete_beta(p, s[0], s[1]);
      // A solution above ½ is returned as x = 1 − y, and near 1 the doubles are
      // too sparse for 1e-12 (a = 512, b = ½, p = 1 − 1e-6: one ulp of x moves
      // I by 1e-8), so the tolerance there adds what one ulp of x changes.
      // student_t_quantile never meets this: it solves for y itself.
      const double one_ulp =
          x > 0.5 ? std::fabs(incomplete_beta(std::nextafter(x, 1.0), s[0], s[1]) - incomplete_beta(x, s[0], s[1])) : 0.0;
      EXPECT_LE(std::fabs(incomplete_beta(x, s[0], s[1]) - p), 1e-12 * p + one_ulp)
          << "a " << s[0] << " b " << s[1] << " p " << p;
    }
  }
  EXPECT_EQ(inverse_incomplete_beta(0.0, 2.0, 3.0), 0.0);
  EXPECT_EQ(inverse_incomplete_beta(1.0, 2.0, 3.0), 1.0);
}

// f must throw std::invalid_argument whose message names `argument`.
template <class F>
void expect_invalid(F f, const std::string& argument) {
  try {
    f();
    ADD_FAILURE() << "no exception for a bad " << argument;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(argument + " must"), std::string::npos) << e.what();
  }
}

TEST(StudentT, InvalidArgumentsThrow) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (double alpha : {0.0, 1.0, -0.1, 1.5, nan}) expect_invalid([&] { student_t_table(alpha); }, "alpha");
  for (int entries : {0, -3}) expect_invalid([&] { student_t_table(0.005, entries); }, "entries");
  for (double p : {0.0, 1.0, -0.5, nan}) expect_invalid([&] { student_t_quantile(p, 3.0); }, "p");
  for (double nu : {0.0, -1.0, inf, nan}) expect_invalid([&] { student_t_quantile(0.9, nu); }, "nu");
  expect_invalid([] { incomplete_beta(-0.1, 1.0, 1.0); }, "x");
  expect_invalid([] { incomplete_beta(0.5, 0.0, 1.0); }, "a");
  expect_invalid([] { inverse_incomplete_beta(1.5, 1.0, 1.0); }, "p");
  expect_invalid([] { inverse_incomplete_beta(0.5, 1.0, -2.0); }, "b");
}

}  // namespace
}  // namespace dn::pipelines
