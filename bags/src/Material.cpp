// Plane-stress incompressible hyperelastic membrane materials.
//
// All derivatives are taken with respect to the Voigt vector of C, c = [C11, C22, C12], in
// which C12 stands for both off-diagonal entries. With E_v = [(c1-1)/2, (c2-1)/2, c3] the
// chain rule is diagonal: dW/dE_v = T dW/dc and d2W/dE_v2 = T (d2W/dc2) T, T = diag(2, 2, 1).
// Working in c keeps the factor 2 of the shear terms in one place (kT).
#include <bags/Material.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "MaterialDetail.h"

namespace bags {
namespace detail {

void checkC(const Mat2& C, const char* who) {
    const double J = C(0, 0) * C(1, 1) - C(0, 1) * C(1, 0);
    if (!(J > 0.0) || !(C(0, 0) + C(1, 1) > 0.0) || !std::isfinite(J)) {
        std::ostringstream os;
        os << who << ": in-plane C is not positive definite (det C = " << J
           << ", tr C = " << C(0, 0) + C(1, 1) << "): the element is inverted or degenerate";
        throw NumericalError(os.str());
    }
}

CScalars calcCScalars(const Mat2& C) {
    CScalars s;
    const double c1 = C(0, 0), c2 = C(1, 1), c3 = 0.5 * (C(0, 1) + C(1, 0));
    s.tr = c1 + c2;
    s.J = c1 * c2 - c3 * c3;
    s.dtr << 1.0, 1.0, 0.0;
    s.dJ << c2, c1, -2.0 * c3;
    s.hJ << 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -2.0;
    s.m = 0.5 * s.tr;
    const double h = 0.5 * (c1 - c2);
    s.q = h * h + c3 * c3;
    s.dm << 0.5, 0.5, 0.0;
    s.dq << h, -h, 2.0 * c3;
    s.hq << 0.5, -0.5, 0.0, -0.5, 0.5, 0.0, 0.0, 0.0, 2.0;
    return s;
}

}  // namespace detail

namespace {

using detail::CScalars;

const Eigen::Vector3d kT(2.0, 2.0, 1.0);  // dE_v/dc is diag(1/2, 1/2, 1); d/dE_v = kT .* d/dc

/// Converts gradient g and Hessian H with respect to c into S_v and D.
void cToVoigt(const Eigen::Vector3d& g, const Eigen::Matrix3d& H, Eigen::Vector3d* S,
              Eigen::Matrix3d* D) {
    if (S) *S = kT.cwiseProduct(g);
    if (D) *D = kT.asDiagonal() * H * kT.asDiagonal();
}

/// Base of the models written as W(I1, I2) with the plane-stress incompressible invariants.
class InvariantMaterial : public MembraneMaterial {
  public:
    double calcEnergy(const Mat2& C, Eigen::Vector3d* S, Eigen::Matrix3d* D) const override {
        detail::checkC(C, "membrane material");
        const CScalars s = detail::calcCScalars(C);
        const double J = s.J, iJ = 1.0 / J, iJ2 = iJ * iJ, iJ3 = iJ2 * iJ;
        const double I1 = s.tr + iJ;
        const double I2 = J + s.tr * iJ;
        double W1 = 0, W2 = 0, W11 = 0, W12 = 0, W22 = 0;
        const double W = calcW(I1, I2, &W1, &W2, &W11, &W12, &W22);
        if (!S && !D) return W;
        // I1 = tr + 1/J,  I2 = J + tr/J
        const Eigen::Vector3d dI1 = s.dtr - iJ2 * s.dJ;
        const Eigen::Vector3d dI2 = s.dJ + iJ * s.dtr - s.tr * iJ2 * s.dJ;
        const Eigen::Vector3d g = W1 * dI1 + W2 * dI2;
        Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
        if (D) {
            const Eigen::Matrix3d dJdJ = s.dJ * s.dJ.transpose();
            const Eigen::Matrix3d hI1 = -iJ2 * s.hJ + 2.0 * iJ3 * dJdJ;
            const Eigen::Matrix3d hI2 =
                s.hJ - iJ2 * (s.dtr * s.dJ.transpose() + s.dJ * s.dtr.transpose()) -
                s.tr * iJ2 * s.hJ + 2.0 * s.tr * iJ3 * dJdJ;
            H = W11 * dI1 * dI1.transpose() +
                W12 * (dI1 * dI2.transpose() + dI2 * dI1.transpose()) +
                W22 * dI2 * dI2.transpose() + W1 * hI1 + W2 * hI2;
        }
        cToVoigt(g, H, S, D);
        return W;
    }

    double calcUniaxialNominalStress(double lambda) const override {
        // P = dW/dlambda with I1 = l^2 + 2/l, I2 = 2 l + 1/l^2: P = 2 (l - l^-2)(W1 + W2 / l).
        const double l = lambda;
        double W1 = 0, W2 = 0, W11, W12, W22;
        calcW(l * l + 2.0 / l, 2.0 * l + 1.0 / (l * l), &W1, &W2, &W11, &W12, &W22);
        return 2.0 * (l - 1.0 / (l * l)) * (W1 + W2 / l);
    }

  protected:
    /// W and its first and second partial derivatives in (I1, I2).
    virtual double calcW(double I1, double I2, double* W1, double* W2, double* W11, double* W12,
                         double* W22) const = 0;
};

class NeoHookean : public InvariantMaterial {
  public:
    explicit NeoHookean(double C10) : m_C10(C10) {
        if (!(C10 > 0.0) || !std::isfinite(C10))
            throw std::invalid_argument("neo-Hookean: C10 = " + std::to_string(C10) +
                                        " Pa; valid: C10 > 0");
    }
    double getInitialShearModulus() const override { return 2.0 * m_C10; }
    std::string getName() const override { return "neo-hookean"; }
    bool getInvariantPolynomial(InvariantPolynomial* law) const override {
        *law = InvariantPolynomial();
        law->C10 = m_C10;
        return true;
    }
    std::unique_ptr<MembraneMaterial> clone() const override {
        return std::make_unique<NeoHookean>(*this);
    }

  protected:
    double calcW(double I1, double, double* W1, double* W2, double* W11, double* W12,
                 double* W22) const override {
        *W1 = m_C10;
        *W2 = *W11 = *W12 = *W22 = 0.0;
        return m_C10 * (I1 - 3.0);
    }

  private:
    double m_C10;
};

class MooneyRivlin : public InvariantMaterial {
  public:
    MooneyRivlin(double C10, double C01) : m_C10(C10), m_C01(C01) {
        if (!(C10 + C01 > 0.0) || !std::isfinite(C10) || !std::isfinite(C01))
            throw std::invalid_argument("Mooney-Rivlin: C10 + C01 = " + std::to_string(C10 + C01) +
                                        " Pa; valid: C10 + C01 > 0 (positive shear modulus)");
    }
    double getInitialShearModulus() const override { return 2.0 * (m_C10 + m_C01); }
    std::string getName() const override { return "mooney-rivlin"; }
    bool getInvariantPolynomial(InvariantPolynomial* law) const override {
        *law = InvariantPolynomial();
        law->C10 = m_C10;
        law->C01 = m_C01;
        return true;
    }
    std::unique_ptr<MembraneMaterial> clone() const override {
        return std::make_unique<MooneyRivlin>(*this);
    }

  protected:
    double calcW(double I1, double I2, double* W1, double* W2, double* W11, double* W12,
                 double* W22) const override {
        *W1 = m_C10;
        *W2 = m_C01;
        *W11 = *W12 = *W22 = 0.0;
        return m_C10 * (I1 - 3.0) + m_C01 * (I2 - 3.0);
    }

  private:
    double m_C10, m_C01;
};

class Yeoh : public InvariantMaterial {
  public:
    Yeoh(double C10, double C20, double C30, double limit)
        : m_C10(C10), m_C20(C20), m_C30(C30), m_limit(limit) {
        if (!(C10 > 0.0) || !std::isfinite(C10) || !std::isfinite(C20) || !std::isfinite(C30))
            throw std::invalid_argument("Yeoh: C10 = " + std::to_string(C10) +
                                        " Pa; valid: C10 > 0 and finite C20, C30");
        if (!(limit > 0.0))
            throw std::invalid_argument("Yeoh: continuation limit I1 - 3 = " +
                                        std::to_string(limit) + "; valid: > 0 (or infinite)");
        if (std::isfinite(limit)) {
            double W1, W2, W11, W12, W22;
            calcPolynomial(limit, &W1, &W11);
            (void)W2, (void)W12, (void)W22;
            if (!(W1 > 0.0))
                throw std::invalid_argument("Yeoh: dW/dI1 = " + std::to_string(W1) +
                                            " Pa at the continuation limit; valid: > 0");
        }
    }
    double getInitialShearModulus() const override { return 2.0 * m_C10; }
    std::string getName() const override { return "yeoh"; }
    bool getInvariantPolynomial(InvariantPolynomial* law) const override {
        law->C10 = m_C10;
        law->C01 = 0.0;
        law->C20 = m_C20;
        law->C30 = m_C30;
        law->continuationLimit = m_limit;
        return true;
    }
    std::unique_ptr<MembraneMaterial> clone() const override {
        return std::make_unique<Yeoh>(*this);
    }

  protected:
    double calcW(double I1, double, double* W1, double* W2, double* W11, double* W12,
                 double* W22) const override {
        const double x = I1 - 3.0;
        *W2 = *W12 = *W22 = 0.0;
        if (x <= m_limit) return calcPolynomial(x, W1, W11);
        // Beyond the limit: W continues with its value and slope there and no curvature lost
        // (W11 = max(W11(limit), 0)), i.e. as a neo-Hookean-like law that stays stable.
        double W1c, W11c;
        const double Wc = calcPolynomial(m_limit, &W1c, &W11c);
        const double k = std::max(W11c, 0.0), dx = x - m_limit;
        *W1 = W1c + k * dx;
        *W11 = k;
        return Wc + dx * (W1c + 0.5 * k * dx);
    }

  private:
    double calcPolynomial(double x, double* W1, double* W11) const {
        *W1 = m_C10 + 2.0 * m_C20 * x + 3.0 * m_C30 * x * x;
        *W11 = 2.0 * m_C20 + 6.0 * m_C30 * x;
        return x * (m_C10 + x * (m_C20 + x * m_C30));
    }
    double m_C10, m_C20, m_C30;
    double m_limit;  ///< I1 - 3 beyond which W continues linearly (infinite: never)
};

/// W = sum_i k_i (G_i + J^-p_i - 3), k_i = 2 mu_i / alpha_i^2, p_i = alpha_i / 2, where
/// G_i = e1^p_i + e2^p_i is a symmetric function of the eigenvalues e of C (= l1^a + l2^a) and
/// J^-p_i = l3^a with l3 = 1 / (l1 l2).
class Ogden : public MembraneMaterial {
  public:
    Ogden(std::vector<double> mu, std::vector<double> alpha)
        : m_mu(std::move(mu)), m_alpha(std::move(alpha)) {
        if (m_mu.empty() || m_mu.size() != m_alpha.size())
            throw std::invalid_argument("Ogden: mu has " + std::to_string(m_mu.size()) +
                                        " values and alpha " + std::to_string(m_alpha.size()) +
                                        "; valid: the same number (1 or more) of each");
        double mu0 = 0.0;
        for (std::size_t i = 0; i < m_mu.size(); ++i) {
            if (!std::isfinite(m_mu[i]) || !std::isfinite(m_alpha[i]) || m_alpha[i] == 0.0)
                throw std::invalid_argument("Ogden: term " + std::to_string(i + 1) +
                                            " has mu = " + std::to_string(m_mu[i]) +
                                            " Pa, alpha = " + std::to_string(m_alpha[i]) +
                                            "; valid: finite values, alpha != 0");
            mu0 += m_mu[i];
        }
        if (!(mu0 > 0.0))
            throw std::invalid_argument("Ogden: sum of mu_i = " + std::to_string(mu0) +
                                        " Pa; valid: > 0 (positive initial shear modulus)");
    }

    double calcEnergy(const Mat2& C, Eigen::Vector3d* S, Eigen::Matrix3d* D) const override {
        detail::checkC(C, "Ogden material");
        const CScalars s = detail::calcCScalars(C);
        double W = 0.0;
        Eigen::Vector3d g = Eigen::Vector3d::Zero();
        Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
        const Eigen::Matrix3d dmdm = s.dm * s.dm.transpose();
        const Eigen::Matrix3d dqdq = s.dq * s.dq.transpose();
        const Eigen::Matrix3d dmdq = s.dm * s.dq.transpose() + s.dq * s.dm.transpose();
        const Eigen::Matrix3d dJdJ = s.dJ * s.dJ.transpose();
        for (std::size_t i = 0; i < m_mu.size(); ++i) {
            const double p = 0.5 * m_alpha[i];
            const double k = 2.0 * m_mu[i] / (m_alpha[i] * m_alpha[i]);
            auto f = [p](double x, int n) { return detail::powDerivative(x, p, n); };
            const detail::SpectralSum G = detail::calcSpectralSum(s.m, s.q, f);
            const double h = std::pow(s.J, -p);  // l3^alpha
            W += k * (G.G + h - 3.0);
            if (S || D) {
                const double h1 = -p * h / s.J;
                g += k * (G.Gm * s.dm + G.Gq * s.dq + h1 * s.dJ);
                if (D) {
                    const double h2 = p * (p + 1.0) * h / (s.J * s.J);
                    H += k * (G.Gmm * dmdm + G.Gmq * dmdq + G.Gqq * dqdq + G.Gq * s.hq + h2 * dJdJ +
                              h1 * s.hJ);
                }
            }
        }
        cToVoigt(g, H, S, D);
        return W;
    }

    double calcUniaxialNominalStress(double lambda) const override {
        double P = 0.0;
        for (std::size_t i = 0; i < m_mu.size(); ++i) {
            const double a = m_alpha[i];
            P += 2.0 * m_mu[i] / a * (std::pow(lambda, a - 1.0) - std::pow(lambda, -0.5 * a - 1.0));
        }
        return P;
    }

    double getInitialShearModulus() const override {
        double mu0 = 0.0;
        for (double m : m_mu) mu0 += m;
        return mu0;
    }
    std::string getName() const override { return "ogden"; }
    std::unique_ptr<MembraneMaterial> clone() const override {
        return std::make_unique<Ogden>(*this);
    }

  private:
    std::vector<double> m_mu;     // [Pa]
    std::vector<double> m_alpha;  // [-]
};

}  // namespace

double detail::powDerivative(double x, double p, int n) {
    // d^n/dx^n x^p = p (p-1) ... (p-n+1) x^(p-n)
    double c = 1.0;
    for (int j = 0; j < n; ++j) c *= (p - j);
    return c == 0.0 ? 0.0 : c * std::pow(x, p - n);
}

double MembraneMaterial::calcNaturalWidth(double e1, double* d1, double* d2) const {
    const double n = 1.0 / std::sqrt(e1);
    if (d1) *d1 = -0.5 * n / e1;
    if (d2) *d2 = 0.75 * n / (e1 * e1);
    return n;
}

double MembraneMaterial::calcUniaxialNominalStress(double lambda) const {
    // Isotropic and incompressible: the strip at C = diag(l^2, 1/l) has S22 = 0, so
    // dW/dl = S11 dE11/dl = S11 l.
    Mat2 C = Mat2::Zero();
    C(0, 0) = lambda * lambda;
    C(1, 1) = 1.0 / lambda;
    Eigen::Vector3d S;
    calcEnergy(C, &S, nullptr);
    return S(0) * lambda;
}

double calcFittedRangeLimit(const MembraneMaterial& material) {
    if (const auto* w = dynamic_cast<const WrinklingMaterial*>(&material))
        return calcFittedRangeLimit(w->getBase());
    InvariantPolynomial law;
    if (material.getInvariantPolynomial(&law)) return law.continuationLimit;
    return std::numeric_limits<double>::infinity();
}

std::unique_ptr<MembraneMaterial> makeNeoHookean(double C10) {
    return std::make_unique<NeoHookean>(C10);
}

std::unique_ptr<MembraneMaterial> makeMooneyRivlin(double C10, double C01) {
    return std::make_unique<MooneyRivlin>(C10, C01);
}

std::unique_ptr<MembraneMaterial> makeYeoh(double C10, double C20, double C30,
                                           double continuationLimit) {
    return std::make_unique<Yeoh>(C10, C20, C30, continuationLimit);
}

std::unique_ptr<MembraneMaterial> makeOgden(const std::vector<double>& mu,
                                            const std::vector<double>& alpha) {
    return std::make_unique<Ogden>(mu, alpha);
}

}  // namespace bags
