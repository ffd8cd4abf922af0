#include <bags/Polynomial.h>

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <string>

namespace bags {

std::vector<double> fitPolynomial(const std::vector<double>& x, const std::vector<double>& y,
                                  int order) {
    if (x.size() != y.size())
        throw std::invalid_argument("fitPolynomial: x has " + std::to_string(x.size()) +
                                    " values but y has " + std::to_string(y.size()));
    if (order < 0)
        throw std::invalid_argument("fitPolynomial: order " + std::to_string(order) +
                                    " must be >= 0");
    const int n = static_cast<int>(x.size());
    if (n < order + 1)
        throw std::invalid_argument("fitPolynomial: order " + std::to_string(order) +
                                    " needs at least " + std::to_string(order + 1) +
                                    " points, got " + std::to_string(n));
    // Fit in t = (x - shift) / scale, then expand back: the raw Vandermonde matrix of, e.g.,
    // masses in grams to the 5th power is poorly conditioned.
    double lo = x[0], hi = x[0];
    for (double v : x) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    const double shift = 0.5 * (lo + hi);
    const double scale = hi > lo ? 0.5 * (hi - lo) : 1.0;
    Eigen::MatrixXd A(n, order + 1);
    Eigen::VectorXd b(n);
    for (int i = 0; i < n; ++i) {
        const double t = (x[i] - shift) / scale;
        double p = 1.0;
        for (int k = 0; k <= order; ++k) {  // column k holds t^k
            A(i, k) = p;
            p *= t;
        }
        b(i) = y[i];
    }
    const Eigen::VectorXd a = A.colPivHouseholderQr().solve(b);  // ascending powers of t
    // Expand sum_k a_k ((x - shift)/scale)^k into ascending powers of x.
    Eigen::VectorXd c = Eigen::VectorXd::Zero(order + 1);
    Eigen::VectorXd basis = Eigen::VectorXd::Zero(order + 1);  // coefficients of t^k in x
    basis(0) = 1.0;
    for (int k = 0; k <= order; ++k) {
        c += a(k) * basis;
        // basis <- basis * (x - shift) / scale
        Eigen::VectorXd next = Eigen::VectorXd::Zero(order + 1);
        for (int j = 0; j < order; ++j) {
            next(j + 1) += basis(j) / scale;
            next(j) -= basis(j) * shift / scale;
        }
        basis = next;
    }
    std::vector<double> out(order + 1);
    for (int k = 0; k <= order; ++k) out[order - k] = c(k);
    return out;
}

double evalPolynomial(const std::vector<double>& coeffs, double x) {
    double v = 0.0;
    for (double c : coeffs) v = v * x + c;
    return v;
}

LinearFit fitLine(const std::vector<double>& x, const std::vector<double>& y) {
    if (x.size() != y.size())
        throw std::invalid_argument("fitLine: x has " + std::to_string(x.size()) +
                                    " values but y has " + std::to_string(y.size()));
    const std::size_t n = x.size();
    if (n < 2)
        throw std::invalid_argument("fitLine: needs at least 2 points, got " + std::to_string(n));
    double mx = 0.0, my = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        mx += x[i];
        my += y[i];
    }
    mx /= n;
    my /= n;
    double sxx = 0.0, sxy = 0.0, syy = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        sxx += (x[i] - mx) * (x[i] - mx);
        sxy += (x[i] - mx) * (y[i] - my);
        syy += (y[i] - my) * (y[i] - my);
    }
    if (!(sxx > 0.0)) throw std::invalid_argument("fitLine: all x values are equal");
    LinearFit f;
    f.slope = sxy / sxx;
    f.intercept = my - f.slope * mx;
    double sse = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const double r = y[i] - (f.slope * x[i] + f.intercept);
        sse += r * r;
    }
    f.r2 = syy > 0.0 ? 1.0 - sse / syy : 1.0;
    return f;
}

}  // namespace bags
