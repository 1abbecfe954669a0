#include "evaluator/statistics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace weathergs::evaluator {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Continued fraction of the incomplete beta function (Numerical Recipes 6.4, modified Lentz).
double beta_continued_fraction(double a, double b, double x) {
  constexpr double kTiny = 1e-300, kEps = 1e-15;
  const double qab = a + b, qap = a + 1, qam = a - 1;
  double c = 1, d = 1 - qab * x / qap;
  if (std::abs(d) < kTiny) d = kTiny;
  d = 1 / d;
  double h = d;
  for (int m = 1; m <= 1000; ++m) {
    const int m2 = 2 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
    d = 1 + aa * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1 + aa / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
    d = 1 + aa * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1 + aa / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1) < kEps) break;
  }
  return h;
}

// I_x(a, b), the regularized incomplete beta function.
double incomplete_beta(double a, double b, double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  const double front =
      std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x));
  // The continued fraction converges fast for x < (a + 1) / (a + b + 2); use the symmetry otherwise.
  if (x < (a + 1) / (a + b + 2)) return front * beta_continued_fraction(a, b, x) / a;
  return 1 - front * beta_continued_fraction(b, a, 1 - x) / b;
}

// P(T <= t) for Student's t with df degrees of freedom.
double student_t_cdf(double t, int df) {
  const double tail = 0.5 * incomplete_beta(0.5 * df, 0.5, df / (df + t * t));
  return t >= 0 ? 1 - tail : tail;
}

}  // namespace

double student_t_quantile(double alpha, int df) {
  WGS_CHECK(df >= 1 && alpha > 0 && alpha < 1);
  const double target = 1 - alpha / 2;
  double lo = 0, hi = 1;
  while (student_t_cdf(hi, df) < target) hi *= 2;
  for (int i = 0; i < 200 && hi - lo > 1e-12; ++i) {
    const double mid = 0.5 * (lo + hi);
    (student_t_cdf(mid, df) < target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double sign_test_p(int k, int n) {
  WGS_CHECK(n >= 1 && k <= n);
  if (k <= 0) return 1;
  // Sum of C(n, i) / 2^n for i = k..n, each term by lgamma so that large n stays finite.
  double p = 0;
  for (int i = k; i <= n; ++i)
    p += std::exp(std::lgamma(n + 1.0) - std::lgamma(i + 1.0) - std::lgamma(n - i + 1.0) - n * std::log(2.0));
  return std::min(1.0, p);
}

MeanInterval mean_ci95(const std::vector<double>& x) {
  MeanInterval r;
  r.n = int(x.size());
  if (x.empty()) return {0, kNaN, kNaN};
  for (double v : x) r.mean += v;
  r.mean /= double(r.n);
  if (r.n < 2 || !std::isfinite(r.mean)) {
    r.half_width = kNaN;
    return r;
  }
  double ss = 0;
  for (double v : x) ss += (v - r.mean) * (v - r.mean);
  const double s = std::sqrt(ss / double(r.n - 1));
  r.half_width = student_t_quantile(0.05, r.n - 1) * s / std::sqrt(double(r.n));
  return r;
}

double kendall_tau_b(const std::vector<double>& a, const std::vector<double>& b) {
  WGS_CHECK(a.size() == b.size());
  const size_t n = a.size();
  double concordant = 0, discordant = 0, ties_a = 0, ties_b = 0;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      const double da = a[i] - a[j], db = b[i] - b[j];
      if (da == 0 && db == 0) continue;  // tied in both: counts in neither denominator term
      if (da == 0) { ties_a += 1; continue; }
      if (db == 0) { ties_b += 1; continue; }
      (da * db > 0 ? concordant : discordant) += 1;
    }
  const double denom = std::sqrt((concordant + discordant + ties_a) * (concordant + discordant + ties_b));
  return denom > 0 ? (concordant - discordant) / denom : kNaN;
}

}  // namespace weathergs::evaluator
