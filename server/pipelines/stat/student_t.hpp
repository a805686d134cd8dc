// Student's t quantiles for the stat pipeline (paper 003, Sakai et al. 2024):
// the Welch test of Alg. 2 compares |θ'_i − θ'_j| / sqrt(Var_i + Var_j) with
// the two-sided critical value t_{1−α/2, ν}, looked up per pixel from a table
// (../shared/papers/IMPLEMENTATION-NOTES.md A.2 P1). The notes ask for the
// table to be generated on the host, not typed in: it comes from the inverse
// regularised incomplete beta function, written here in double precision.
#pragma once

#include <vector>

namespace dn::pipelines {

// Regularised incomplete beta I_x(a, b) for x in [0, 1], a, b > 0
// (Lentz's continued fraction). Throws std::invalid_argument otherwise.
double incomplete_beta(double x, double a, double b);

// The x in [0, 1] with I_x(a, b) = p, for p in [0, 1], a, b > 0.
// Throws std::invalid_argument otherwise.
double inverse_incomplete_beta(double p, double a, double b);

// The quantile t_{p,ν} of Student's t distribution: P(T ≤ t) = p, for
// p in (0, 1) and real, finite ν > 0. Against 60-digit arithmetic the
// relative error stayed below 5e-12 for ν in [0.1, 1e6] and p in
// [1e-6, 1 − 1e-6]. Throws std::invalid_argument otherwise.
double student_t_quantile(double p, double nu);

// The stat pipeline's critical-value table (paper 003 Alg. 2; notes A.2 P1):
// entry k holds the two-sided t_{1−α/2, ν = k+1}, so n samples per side
// (ν = 2n − 2) read index 2n − 3, clamped to the last entry. α = 0.005 and
// 1024 entries are the paper's. Throws std::invalid_argument unless alpha is
// in (0, 1) and entries >= 1.
std::vector<float> student_t_table(double alpha, int entries = 1024);

}  // namespace dn::pipelines
