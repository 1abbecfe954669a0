// The statistics behind the paper-protocol tables: Student-t confidence intervals over seeds, paired
// differences, the sign test and Kendall's rank correlation.
#pragma once

#include <vector>

namespace weathergs::evaluator {

// The two-sided (1 - alpha) Student-t quantile t_{1 - alpha/2, df}, df >= 1 (e.g. 4.303 for df 2 at
// alpha 0.05). Inverts the t distribution's CDF, written with the regularized incomplete beta function
// (Abramowitz & Stegun 26.7.1 and 26.5.8), by bisection to 1e-12.
double student_t_quantile(double alpha, int df);

// A sample's mean and the half-width of its 95% Student-t confidence interval,
// t_{0.975, n-1} * s / sqrt(n) with s the sample standard deviation (NaN for fewer than 2 values).
struct MeanInterval {
  int n = 0;
  double mean = 0;
  double half_width = 0;  // NaN when n < 2
};
MeanInterval mean_ci95(const std::vector<double>& x);

// The one-sided sign test: P(X >= k) for X ~ Binomial(n, 1/2), i.e. the chance that k or more of n
// paired differences share a sign when each sign is a fair coin. 1 for k <= 0; n >= 1, k <= n.
double sign_test_p(int k, int n);

// Kendall's tau-b between two paired samples (ties counted as in Kendall 1945): +1 for the same
// order, -1 for the reverse; NaN for fewer than 2 pairs or when either sample is constant.
double kendall_tau_b(const std::vector<double>& a, const std::vector<double>& b);

}  // namespace weathergs::evaluator
