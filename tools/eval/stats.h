// Small statistics toolbox for the evaluation harness: sample moments, robust location/scale, Student-t
// and chi-square tail probabilities (to test a mean against zero with few runs), Fisher's combination of
// independent p-values. Everything is in double; empty inputs are an error (std::invalid_argument).
#pragma once
#include <vector>

namespace mlt::eval {

double mean(const std::vector<double>& x);
// Sample standard deviation (divisor n - 1); 0 for a single value.
double stddev(const std::vector<double>& x);
double median(std::vector<double> x);
// Median absolute deviation from the median (unscaled; multiply by 1.4826 for a normal sigma).
double mad(const std::vector<double>& x);

// Regularized incomplete beta function I_x(a, b) (Numerical Recipes' continued fraction, Lentz).
double incompleteBeta(double a, double b, double x);
// Two-sided tail probability P(|T| >= |t|) of Student's t with `dof` degrees of freedom:
//   p = I_{dof / (dof + t^2)}(dof / 2, 1 / 2).
double studentTwoSidedP(double t, double dof);
// Upper tail P(X >= x) of a chi-square variable with an even number 2k of degrees of freedom:
//   exp(-x/2) * sum_{i<k} (x/2)^i / i!   (closed form for even dof).
double chiSquareUpperEvenDof(double x, int dof);
// Fisher's method: X = -2 sum ln p_i ~ chi^2(2n) under the joint null; returns its upper tail.
double fisherCombine(const std::vector<double>& pValues);

}  // namespace mlt::eval
