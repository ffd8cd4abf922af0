// Tension-field relaxation (Pipkin 1986) of an isotropic membrane material. The natural width
// n(e1) comes from the base material (e1^(-1/2) when incompressible; 1 - nu (e1 - 1) for the
// compressible St. Venant-Kirchhoff sheet).
//
// With e1 >= e2 the eigenvalues of the in-plane C (e = lambda^2):
//   slack     e1 <= 1                 W = 0
//   wrinkled  e1 > 1, e2 < e1^(-1/2)  W = w(e1) := W_base(diag(e1, e1^(-1/2)))
//   taut      otherwise               W = W_base(C)
// e1^(-1/2) is the natural width: the lateral stretch of a free uniaxial strip of an isotropic
// incompressible sheet. There S22 = 0, so W is C1 across the taut/wrinkled boundary; and
// w(1) = w'(1) = 0 makes it C1 across the wrinkled/slack boundary too.
//
// In the wrinkled state W depends on C through e1 only. As a function of c = [C11, C22, C12]:
// e1 = m + sqrt(q) (see MaterialDetail.h), so de1/dc = dm + dq / (2 r) (the Voigt form of
// n1 n1^T) and d2e1/dc2 = hq / (2 r) - dq dq^T / (4 r^3): the 1/(e1 - e2) term of the
// eigenvalue's second derivative. r = (e1 - e2)/2 > 0 in that state (e1 > 1 > e2), and the
// product w'(e1) d2e1/dc2 stays bounded as C -> I because w'(e1) ~ (e1 - 1) there.
#include <bags/Material.h>

#include <cmath>
#include <stdexcept>

#include "MaterialDetail.h"

namespace bags {

namespace {
const Eigen::Vector3d kT(2.0, 2.0, 1.0);  // d/dE_v = kT .* d/dc

enum State { Taut = 0, Wrinkled = 1, Slack = 2 };

State findState(const MembraneMaterial& base, double e1, double e2) {
    if (e1 <= 1.0) return Slack;
    if (e2 < base.calcNaturalWidth(e1, nullptr, nullptr)) return Wrinkled;
    return Taut;
}

void calcEigenvalues(const detail::CScalars& s, double* e1, double* e2) {
    const double r = std::sqrt(std::max(s.q, 0.0));
    *e1 = s.m + r;
    *e2 = s.m - r;
}
}  // namespace

WrinklingMaterial::WrinklingMaterial(std::unique_ptr<MembraneMaterial> base, double residual)
    : m_base(std::move(base)), m_residual(residual) {
    if (!m_base) throw std::invalid_argument("WrinklingMaterial: base material is null");
    if (!(residual >= 0.0) || !std::isfinite(residual))
        throw std::invalid_argument("WrinklingMaterial: residual = " + std::to_string(residual) +
                                    "; valid: >= 0 (typically 1e-4 to 1e-2)");
}

WrinklingMaterial::WrinklingMaterial(std::unique_ptr<MembraneMaterial> base, double residual,
                                     std::unique_ptr<MembraneMaterial> residualMaterial)
    : WrinklingMaterial(std::move(base), residual) {
    if (!residualMaterial)
        throw std::invalid_argument("WrinklingMaterial: residual material is null");
    m_residualMaterial = std::move(residualMaterial);
}

WrinklingMaterial::WrinklingMaterial(const WrinklingMaterial& other)
    : m_base(other.m_base->clone()),
      m_residual(other.m_residual),
      m_residualMaterial(other.m_residualMaterial ? other.m_residualMaterial->clone() : nullptr) {}

void WrinklingMaterial::calcPrincipalStretches(const Mat2& C, double* lambda1, double* lambda2) {
    const detail::CScalars s = detail::calcCScalars(C);
    double e1, e2;
    calcEigenvalues(s, &e1, &e2);
    *lambda1 = std::sqrt(std::max(e1, 0.0));
    *lambda2 = std::sqrt(std::max(e2, 0.0));
}

int WrinklingMaterial::calcState(const Mat2& C) const {
    const detail::CScalars s = detail::calcCScalars(C);
    double e1, e2;
    calcEigenvalues(s, &e1, &e2);
    return findState(*m_base, e1, e2);
}

double WrinklingMaterial::calcEnergy(const Mat2& C, Eigen::Vector3d* S, Eigen::Matrix3d* D) const {
    detail::checkC(C, "wrinkling membrane material");
    const detail::CScalars s = detail::calcCScalars(C);
    double e1, e2;
    calcEigenvalues(s, &e1, &e2);
    const State state = findState(*m_base, e1, e2);

    // Taut or slack with the base as residual material: one base call, scaled.
    if (!m_residualMaterial && state != Wrinkled) {
        const double f = (state == Taut ? 1.0 : 0.0) + m_residual;
        if (f == 0.0) {
            if (S) S->setZero();
            if (D) D->setZero();
            return 0.0;
        }
        const double W = f * m_base->calcEnergy(C, S, D);
        if (S) *S *= f;
        if (D) *D *= f;
        return W;
    }
    double W = 0.0;
    if (S) S->setZero();
    if (D) D->setZero();
    if (state == Taut) {
        W = m_base->calcEnergy(C, S, D);
    } else if (state == Wrinkled) {
        // w(e) = W_base(diag(e, n(e))), n the natural width; its e-derivatives by the chain
        // rule through E_v(e) = (e - 1, n(e) - 1, 0) / 2.
        double n1 = 0.0, n2 = 0.0;
        Mat2 Cu = Mat2::Zero();
        Cu(0, 0) = e1;
        Cu(1, 1) = m_base->calcNaturalWidth(e1, &n1, &n2);
        Eigen::Vector3d Su;
        Eigen::Matrix3d Du;
        W = m_base->calcEnergy(Cu, (S || D) ? &Su : nullptr, D ? &Du : nullptr);
        if (S || D) {
            const Eigen::Vector3d a(0.5, 0.5 * n1, 0.0);  // dE_v/de
            const double w1 = a.dot(Su);
            const double r = std::sqrt(std::max(s.q, 0.0));
            const Eigen::Vector3d g = s.dm + s.dq / (2.0 * r);  // de1/dc
            if (S) *S = w1 * kT.cwiseProduct(g);
            if (D) {
                const double w2 = a.dot(Du * a) + Su(1) * 0.5 * n2;  // d2E22/de2 = n''/2
                const Eigen::Matrix3d H =
                    w2 * g * g.transpose() +
                    w1 * (s.hq / (2.0 * r) - s.dq * s.dq.transpose() / (4.0 * r * r * r));
                *D = kT.asDiagonal() * H * kT.asDiagonal();
            }
        }
    }
    if (m_residual > 0.0) {
        Eigen::Vector3d Sr;
        Eigen::Matrix3d Dr;
        W += m_residual * getResidualMaterial().calcEnergy(C, S ? &Sr : nullptr, D ? &Dr : nullptr);
        if (S) *S += m_residual * Sr;
        if (D) *D += m_residual * Dr;
    }
    return W;
}

double WrinklingMaterial::getInitialShearModulus() const {
    // Small taut strains: W = (1 + residual) W_base near C = I.
    return m_base->getInitialShearModulus() +
           m_residual * getResidualMaterial().getInitialShearModulus();
}

std::string WrinklingMaterial::getName() const {
    return "tension-field(" + m_base->getName() + ")";
}

std::unique_ptr<MembraneMaterial> WrinklingMaterial::clone() const {
    return std::make_unique<WrinklingMaterial>(*this);
}

}  // namespace bags
