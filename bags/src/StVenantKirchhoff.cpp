#include <bags/StVenantKirchhoff.h>

#include <stdexcept>

namespace bags {

namespace {

class StVenantKirchhoff final : public MembraneMaterial {
  public:
    StVenantKirchhoff(double E, double nu) : m_E(E), m_nu(nu) {
        if (!(E > 0.0)) throw std::invalid_argument("St. Venant-Kirchhoff: E must be positive");
        if (!(nu > -1.0 && nu < 0.5))
            throw std::invalid_argument("St. Venant-Kirchhoff: nu must be in (-1, 0.5)");
        const double c = E / (1.0 - nu * nu);
        m_D << c, c * nu, 0.0, c * nu, c, 0.0, 0.0, 0.0, c * 0.5 * (1.0 - nu);
    }
    double calcEnergy(const Mat2& C, Eigen::Vector3d* S, Eigen::Matrix3d* D) const override {
        const Eigen::Vector3d Ev(0.5 * (C(0, 0) - 1.0), 0.5 * (C(1, 1) - 1.0), C(0, 1));
        const Eigen::Vector3d Sv = m_D * Ev;
        if (S) *S = Sv;
        if (D) *D = m_D;
        return 0.5 * Ev.dot(Sv);
    }
    // Free strip: S22 = 0 gives E22 = -nu E11, i.e. e2 = 1 - nu (e1 - 1).
    double calcNaturalWidth(double e1, double* d1, double* d2) const override {
        if (d1) *d1 = -m_nu;
        if (d2) *d2 = 0.0;
        return 1.0 - m_nu * (e1 - 1.0);
    }
    double getInitialShearModulus() const override { return m_E / (2.0 * (1.0 + m_nu)); }
    std::string getName() const override { return "st-venant-kirchhoff"; }
    std::unique_ptr<MembraneMaterial> clone() const override {
        return std::make_unique<StVenantKirchhoff>(*this);
    }

  private:
    double m_E, m_nu;
    Eigen::Matrix3d m_D;
};

}  // namespace

std::unique_ptr<MembraneMaterial> makeStVenantKirchhoff(double E, double nu) {
    return std::make_unique<StVenantKirchhoff>(E, nu);
}

}  // namespace bags
