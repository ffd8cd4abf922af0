#pragma once
/// @file Least-squares polynomials and straight lines, as used to fit stiffness against gas
/// mass k(m) and the slope of a force-displacement range.

#include <vector>

namespace bags {

/// Least-squares polynomial of the given order through (x, y), solved by a column-pivoted
/// Householder QR of the Vandermonde matrix (x is centred and scaled internally for
/// conditioning; the returned coefficients are for the raw x).
/// @return order+1 coefficients, highest power first: y = c[0] x^order + ... + c[order].
/// @throws std::invalid_argument if x and y differ in size, order < 0, or there are fewer than
///   order+1 points.
std::vector<double> fitPolynomial(const std::vector<double>& x, const std::vector<double>& y,
                                  int order);

/// Value of the polynomial with coefficients highest power first (Horner); 0 if empty.
double evalPolynomial(const std::vector<double>& coeffs, double x);

/// A least-squares straight line y = slope x + intercept.
struct LinearFit {
    double slope = 0.0;      ///< [unit of y / unit of x]
    double intercept = 0.0;  ///< [unit of y]
    double r2 = 0.0;         ///< coefficient of determination (1 if y is constant and fitted)
};

/// Least-squares line through (x, y).
/// @throws std::invalid_argument if sizes differ, fewer than 2 points, or all x are equal.
LinearFit fitLine(const std::vector<double>& x, const std::vector<double>& y);

}  // namespace bags
