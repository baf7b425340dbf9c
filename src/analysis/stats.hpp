// the statistics behind the figures (SPEC §8.3, ANALYSIS.md §3): means, sample sd and SEM (n − 1),
// seeded percentile-bootstrap CIs with numpy's linear quantile, Welch's and Student's t-tests with the
// two-sided p from the regularized incomplete beta function, and the exact two-sided Mann–Whitney U test.
#pragma once

#include <cstdint>
#include <span>

namespace divcoll::analysis {

double mean(std::span<const double> x);       // NaN when x is empty
double sample_sd(std::span<const double> x);  // ddof = 1; NaN when n < 2
double sem(std::span<const double> x);        // sample_sd / √n; NaN when n < 2

// numpy's default "linear" quantile of sorted values: the value at position q·(n−1), interpolated
double quantile_linear(std::span<const double> sorted, double q);

struct Interval {
  double lo, hi;
};

// percentile bootstrap of the mean: `resamples` resamples of size n drawn with replacement from a
// divcoll::Rng seeded by `seed`; the (1−level)/2 and (1+level)/2 linear quantiles of their means.
// {NaN, NaN} when x is empty; {x0, x0} when n = 1.
Interval bootstrap_ci(std::span<const double> x, uint64_t seed, int resamples = 1000, double level = 0.95);

struct TestResult {
  double statistic;  // t (or U)
  double df;         // degrees of freedom (NaN for U)
  double p;          // two-sided
};

// Welch's unequal-variance t-test, a vs b; all NaN when either has fewer than 2 values or both variances are 0
TestResult welch_t_test(std::span<const double> a, std::span<const double> b);
// Student's pooled-variance t-test (for comparison; Welch is the primary test)
TestResult student_t_test(std::span<const double> a, std::span<const double> b);

// two-sided p of Student's t distribution with df degrees of freedom: I_{df/(df+t²)}(df/2, 1/2)
double t_two_sided_p(double t, double df);

// the regularized incomplete beta function I_x(a, b), by Lentz's continued fraction (Numerical Recipes §6.4)
double incomplete_beta_regularized(double x, double a, double b);

// Mann–Whitney U (U of a, the count of pairs with a > b plus half the ties), two-sided p exact by the
// counting recursion when there are no ties and n1, n2 ≤ 50, else the normal approximation with continuity
// correction (tie-corrected variance)
TestResult mann_whitney_u(std::span<const double> a, std::span<const double> b);

}  // namespace divcoll::analysis
