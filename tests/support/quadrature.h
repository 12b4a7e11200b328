#pragma once
/// Adaptive Simpson quadrature in double precision: the oracles of the reference tests.

#include <cmath>
#include <functional>

namespace scatterlab::testing {

/// One adaptive Simpson step on [a, b] (f at a, the midpoint and b given, `whole` the Simpson
/// estimate of the interval), refined until the Richardson error is below 15·tol.
inline double simpson(const std::function<double(double)>& f, double a, double b, double fa,
                      double fm, double fb, double whole, double tol, int depth) {
  const double m = 0.5 * (a + b), lm = 0.5 * (a + m), rm = 0.5 * (m + b);
  const double flm = f(lm), frm = f(rm);
  const double left = (m - a) / 6 * (fa + 4 * flm + fm), right = (b - m) / 6 * (fm + 4 * frm + fb);
  if (depth <= 0 || std::abs(left + right - whole) <= 15 * tol)
    return left + right + (left + right - whole) / 15;
  return simpson(f, a, m, fa, flm, fm, left, tol / 2, depth - 1) +
         simpson(f, m, b, fm, frm, fb, right, tol / 2, depth - 1);
}

/// ∫_a^b f to absolute tolerance `tol`, at most `depth` bisections deep.
inline double integrate(const std::function<double(double)>& f, double a, double b,
                        double tol = 1e-13, int depth = 50) {
  const double fa = f(a), fb = f(b), fm = f(0.5 * (a + b));
  return simpson(f, a, b, fa, fm, fb, (b - a) / 6 * (fa + 4 * fm + fb), tol, depth);
}

}  // namespace scatterlab::testing
