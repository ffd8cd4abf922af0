#pragma once
// Internal helpers shared by Material.cpp, Wrinkling.cpp and MaterialFit.cpp: scalar functions
// of the Voigt vector c = [C11, C22, C12] of the in-plane C with their gradients and Hessians.

#include <bags/Types.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace bags::detail {

/// Throws NumericalError unless C is positive definite.
void checkC(const Mat2& C, const char* who);

/// tr C, det C, and the eigenvalue mean m = tr/2 and squared half-gap q = ((e1-e2)/2)^2, each
/// with its gradient (and Hessian where not zero) with respect to c.
struct CScalars {
    double tr, J, m, q;
    Eigen::Vector3d dtr, dJ, dm, dq;
    Eigen::Matrix3d hJ, hq;
};
CScalars calcCScalars(const Mat2& C);

/// d^n/dx^n of x^p.
double powDerivative(double x, double p, int n);

/// G(m, q) = f(m + sqrt q) + f(m - sqrt q) = sum over the eigenvalues of C of f(e), and its
/// partial derivatives; robust at q -> 0 (equal eigenvalues).
struct SpectralSum {
    double G, Gm, Gq, Gmm, Gmq, Gqq;
};

/// f(x, n) returns the n-th derivative of f at x (n up to 8).
template <class F>
SpectralSum calcSpectralSum(double m, double q, const F& f) {
    // G is even in r = sqrt q, hence smooth in q. Its q-derivatives are divided differences
    // that lose digits as r -> 0; there the Taylor series in r about m takes over (3 terms:
    // truncation ~ (r/m)^6 < 1e-18 at the switch, where the divided differences lose ~1e-10).
    SpectralSum s;
    const double r = std::sqrt(std::max(q, 0.0));
    const double a = m + r, b = m - r;
    s.G = f(a, 0) + f(b, 0);
    s.Gm = f(a, 1) + f(b, 1);
    s.Gmm = f(a, 2) + f(b, 2);
    if (r > 1e-3 * m) {
        const double d1 = f(a, 1) - f(b, 1);
        s.Gq = d1 / (2.0 * r);
        s.Gmq = (f(a, 2) - f(b, 2)) / (2.0 * r);
        s.Gqq = (s.Gmm * r - d1) / (4.0 * r * r * r);
    } else {
        const double r2 = r * r, r4 = r2 * r2;
        s.Gq = f(m, 2) + f(m, 4) * r2 / 6.0 + f(m, 6) * r4 / 120.0;
        s.Gmq = f(m, 3) + f(m, 5) * r2 / 6.0 + f(m, 7) * r4 / 120.0;
        s.Gqq = f(m, 4) / 6.0 + f(m, 6) * r2 / 60.0 + f(m, 8) * r4 / 1680.0;
    }
    return s;
}

}  // namespace bags::detail
