#pragma once
// Helpers shared by the material tests: the seed's Yeoh constants, building C from principal
// stretches, and perturbing one Voigt strain component.
#include <bags/Material.h>
#include <bags/Types.h>

#include <cmath>

namespace bags::test {

// Seed study, Table 2 [Pa].
constexpr double kC10 = 31.587917e6, kC20 = -0.76582566e6, kC30 = -3.06587618e6;

/// C = R diag(l1^2, l2^2) R^T.
inline Mat2 makeC(double l1, double l2, double angle) {
    Mat2 R;
    R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
    Mat2 L = Mat2::Zero();
    L(0, 0) = l1 * l1;
    L(1, 1) = l2 * l2;
    return R * L * R.transpose();
}

/// C + the change of E_v component k by h (E_v = [E11, E22, 2 E12]).
inline Mat2 perturb(const Mat2& C, int k, double h) {
    Mat2 Cp = C;
    if (k == 0) Cp(0, 0) += 2.0 * h;
    if (k == 1) Cp(1, 1) += 2.0 * h;
    if (k == 2) {
        Cp(0, 1) += h;
        Cp(1, 0) += h;
    }
    return Cp;
}

/// Central differences of W (giving S) and of S (giving D) in the Voigt convention, step h.
inline void calcFiniteDifferenceDerivatives(const MembraneMaterial& mat, const Mat2& C, double h,
                                            Eigen::Vector3d* Sfd, Eigen::Matrix3d* Dfd) {
    for (int k = 0; k < 3; ++k) {
        Eigen::Vector3d Sp, Sm;
        const double Wp = mat.calcEnergy(perturb(C, k, h), &Sp, nullptr);
        const double Wm = mat.calcEnergy(perturb(C, k, -h), &Sm, nullptr);
        (*Sfd)(k) = (Wp - Wm) / (2.0 * h);
        Dfd->col(k) = (Sp - Sm) / (2.0 * h);
    }
}

}  // namespace bags::test
