// Fabric anisotropy (docs/materials.md#fabric-anisotropy): an isotropic matrix plus two yarn
// families that carry tension only. With c = [C11, C22, C12] and a unit yarn direction a,
// the yarn's Green strain E_a = (a . C a - 1)/2 is linear in c, dE_a/dc = g/2 with
// g = [a1^2, a2^2, 2 a1 a2]; with T = diag(2, 2, 1) the Voigt stress of k/2 <E_a>^2 is
// k <E_a> T g/2 = k <E_a> [a1^2, a2^2, a1 a2] and its tangent k H(E_a) v v^T, v = T g/2.
#include <bags/Material.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace bags {

namespace {
// Adds one family's energy, stress and tangent; returns its energy.
double addYarn(const Mat2& C, double k, double angle, Eigen::Vector3d* S, Eigen::Matrix3d* D) {
    if (!(k > 0.0)) return 0.0;
    const double a1 = std::cos(angle), a2 = std::sin(angle);
    const double E = 0.5 * (a1 * a1 * C(0, 0) + a2 * a2 * C(1, 1) + 2.0 * a1 * a2 * C(0, 1) - 1.0);
    if (!(E > 0.0)) return 0.0;  // a yarn in compression buckles (crimps): no stress
    const Eigen::Vector3d v(a1 * a1, a2 * a2, a1 * a2);
    if (S) *S += k * E * v;
    if (D) *D += k * v * v.transpose();
    return 0.5 * k * E * E;
}
}  // namespace

void FabricAnisotropy::validate() const {
    auto check = [](const char* name, double k) {
        if (!(k >= 0.0 && k <= kMaxModulus)) {
            std::ostringstream s;
            s << "fabric anisotropy: " << name << " = " << k << " Pa; valid: 0 to " << kMaxModulus
              << " Pa (the yarns' tangent modulus in Green strain, 0: none)";
            throw std::invalid_argument(s.str());
        }
    };
    check("warpModulus", warpModulus);
    check("weftModulus", weftModulus);
    if (!(std::abs(angle) <= 0.5 * M_PI + 1e-12)) {
        std::ostringstream s;
        s << "fabric anisotropy: angle = " << angle << " rad; valid: -pi/2 to pi/2 (the warp's "
          << "angle from the panel's reference direction)";
        throw std::invalid_argument(s.str());
    }
}

FabricMaterial::FabricMaterial(std::unique_ptr<MembraneMaterial> matrix,
                               const FabricAnisotropy& yarns)
    : m_matrix(std::move(matrix)), m_yarns(yarns) {
    if (!m_matrix) throw std::invalid_argument("FabricMaterial: matrix material is null");
    if (!m_matrix->isIsotropic())
        throw std::invalid_argument("FabricMaterial: the matrix must be isotropic");
    m_yarns.validate();
}

FabricMaterial::FabricMaterial(const FabricMaterial& other)
    : m_matrix(other.m_matrix->clone()), m_yarns(other.m_yarns) {}

double FabricMaterial::calcEnergy(const Mat2& C, Eigen::Vector3d* S, Eigen::Matrix3d* D) const {
    double W = m_matrix->calcEnergy(C, S, D);
    W += addYarn(C, m_yarns.warpModulus, m_yarns.angle, S, D);
    W += addYarn(C, m_yarns.weftModulus, m_yarns.angle + 0.5 * M_PI, S, D);
    return W;
}

double FabricMaterial::getInitialShearModulus() const { return m_matrix->getInitialShearModulus(); }

std::string FabricMaterial::getName() const { return m_matrix->getName() + "+yarns"; }

std::unique_ptr<MembraneMaterial> FabricMaterial::clone() const {
    return std::make_unique<FabricMaterial>(*this);
}

std::unique_ptr<MembraneMaterial> makeRelaxedMaterial(const MembraneMaterial& base,
                                                      double residual) {
    if (const auto* fabric = dynamic_cast<const FabricMaterial*>(&base))
        return std::make_unique<FabricMaterial>(
            std::make_unique<WrinklingMaterial>(fabric->getMatrix().clone(), residual),
            fabric->getYarns());
    return std::make_unique<WrinklingMaterial>(base.clone(), residual);
}

}  // namespace bags
