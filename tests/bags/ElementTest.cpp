// Membrane element (constant-strain triangle, total Lagrangian): gradient and tangent against
// central finite differences, and the uniform-stretch patch test.
#include "TestMeshes.h"

#include <bags/Material.h>
#include <bags/EquilibriumSolver.h>
#include <bags/StVenantKirchhoff.h>

#include <gtest/gtest.h>

#include <Eigen/SparseCore>

#include <random>

using namespace bags;

namespace {

double energy(const MembraneModel& m, const Eigen::Matrix3Xd& x) {
    EnergyAccumulator acc(m.getMesh().getNumNodes());
    acc.wantHessian = false;
    m.addMembraneEnergy(x, acc);
    return acc.energy;
}

Eigen::VectorXd gradient(const MembraneModel& m, const Eigen::Matrix3Xd& x) {
    EnergyAccumulator acc(m.getMesh().getNumNodes());
    acc.wantHessian = false;
    m.addMembraneEnergy(x, acc);
    return acc.grad;
}

Eigen::MatrixXd hessian(const MembraneModel& m, const Eigen::Matrix3Xd& x) {
    const int n = 3 * m.getMesh().getNumNodes();
    EnergyAccumulator acc(m.getMesh().getNumNodes());
    m.addMembraneEnergy(x, acc);
    Eigen::SparseMatrix<double> H(n, n);
    H.setFromTriplets(acc.hess.begin(), acc.hess.end());
    return Eigen::MatrixXd(H);
}

// Checks gradient = FD(energy) and Hessian = FD(gradient) at a random stretched state.
void checkTangents(const MembraneModel& model, double stretch, unsigned seed) {
    const Mesh& mesh = model.getMesh();
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::Matrix3Xd x = mesh.X;
    x.row(0) *= stretch;
    x.row(1) *= 1.0 + 0.5 * (stretch - 1.0);
    for (int i = 0; i < x.cols(); ++i)
        for (int d = 0; d < 3; ++d) x(d, i) += 0.02 * 0.1 * u(rng);  // 2 mm noise on 100 mm
    const Eigen::VectorXd g = gradient(model, x);
    const Eigen::MatrixXd H = hessian(model, x);
    const double h = 1e-7;
    Eigen::VectorXd gfd(g.size());
    Eigen::MatrixXd Hfd(H.rows(), H.cols());
    for (int k = 0; k < g.size(); ++k) {
        Eigen::Matrix3Xd xp = x, xm = x;
        xp.data()[k] += h;
        xm.data()[k] -= h;
        gfd(k) = (energy(model, xp) - energy(model, xm)) / (2 * h);
        Hfd.col(k) = (gradient(model, xp) - gradient(model, xm)) / (2 * h);
    }
    // Central differences: truncation O(h^2), roundoff ~ eps*E/h; 1e-5 relative to the norms.
    EXPECT_LT((g - gfd).norm(), 1e-5 * g.norm()) << "gradient vs FD";
    EXPECT_LT((H - Hfd).norm(), 1e-5 * H.norm()) << "Hessian vs FD";
    EXPECT_LT((H - H.transpose()).norm(), 1e-12 * H.norm()) << "Hessian symmetric";
}

}  // namespace

TEST(MembraneElement, TangentMatchesFiniteDifferencesStVenantKirchhoff) {
    MembraneModel model(test::makePatch(2, 0.1), makeStVenantKirchhoff(588e6, 0.4), 0.6e-3);
    checkTangents(model, 1.05, 1);
}

TEST(MembraneElement, TangentMatchesFiniteDifferencesSeedYeohWithWrinkling) {
    std::shared_ptr<MembraneMaterial> yeoh(
        new WrinklingMaterial(makeYeoh(31.587917e6, -0.76582566e6, -3.06587618e6), 1e-3));
    MembraneModel model(test::makePatch(2, 0.1), yeoh, 0.2e-3);
    checkTangents(model, 1.03, 2);  // taut, mostly
    checkTangents(model, 0.97, 3);  // compressed: wrinkled and slack elements
}

TEST(MembraneElement, UniformStretchPatchHasNoInteriorForceAndExactStress) {
    // Patch test: x = F X for a homogeneous in-plane deformation. Interior nodes carry no net
    // force (machine precision relative to the boundary forces), every element's energy
    // density is W(C) of the material, and the boundary forces integrate the exact traction.
    const double L = 0.1, t = 0.2e-3;
    auto mat = std::shared_ptr<MembraneMaterial>(makeStVenantKirchhoff(588e6, 0.4));
    MembraneModel model(test::makePatch(4, L), mat, t);
    Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
    F(0, 0) = 1.04;
    F(1, 1) = 1.01;
    F(0, 1) = 0.02;
    const Eigen::Matrix3Xd x = F * model.getMesh().X;
    const Eigen::VectorXd g = gradient(model, x);
    double maxInterior = 0.0, maxBoundary = 0.0;
    for (int j = 0; j <= 4; ++j)
        for (int i = 0; i <= 4; ++i) {
            const double f = g.segment<3>(3 * (j * 5 + i)).norm();
            if (i > 0 && i < 4 && j > 0 && j < 4)
                maxInterior = std::max(maxInterior, f);
            else
                maxBoundary = std::max(maxBoundary, f);
        }
    EXPECT_LT(maxInterior, 1e-10 * maxBoundary);
    const Eigen::Matrix2d C = F.topLeftCorner<2, 2>().transpose() * F.topLeftCorner<2, 2>();
    Eigen::Vector3d S;
    const double W = mat->calcEnergy(C, &S, nullptr);
    EXPECT_NEAR(energy(model, x), W * L * L * t, 1e-12 * W * L * L * t);
    // Net force on the right edge (x = L) = P n A: first Piola traction P = F S, n = e_x.
    Eigen::Matrix2d Sm;
    Sm << S(0), S(2), S(2), S(1);
    const Eigen::Vector2d traction = F.topLeftCorner<2, 2>() * Sm * Eigen::Vector2d(1, 0);
    Eigen::Vector2d right = Eigen::Vector2d::Zero();
    for (int j = 0; j <= 4; ++j) right += g.segment<2>(3 * (j * 5 + 4));
    EXPECT_NEAR(right(0), traction(0) * L * t, 1e-10 * traction.norm() * L * t);
    EXPECT_NEAR(right(1), traction(1) * L * t, 1e-10 * traction.norm() * L * t);
}

TEST(MembraneElement, TangentMatchesFiniteDifferencesCompressibleWithWrinkling) {
    // St. Venant-Kirchhoff (nu = 0.4) under the tension-field law with its own natural width
    // e2 = 1 - nu (e1 - 1): taut, wrinkled and slack elements.
    std::shared_ptr<MembraneMaterial> m(
        new WrinklingMaterial(makeStVenantKirchhoff(588e6, 0.4), 1e-3));
    MembraneModel model(test::makePatch(2, 0.1), m, 0.6e-3);
    checkTangents(model, 1.03, 4);
    checkTangents(model, 0.98, 5);
}

TEST(WrinklingCompressible, FreeStripOfStVenantKirchhoffCarriesNoLateralStress) {
    // A strip stretched to l1 = 1.05 with its lateral stretch below the natural width
    // sqrt(1 - 0.4 (l1^2 - 1)) is wrinkled: S22 = 0 and S11 is the base's plane-stress
    // uniaxial stress E E11 (exact for SVK). Tolerance 1e-9 relative (residual 0).
    const double E = 588e6, nu = 0.4, e1 = 1.05 * 1.05;
    WrinklingMaterial w(makeStVenantKirchhoff(E, nu), 0.0);
    Mat2 C = Mat2::Zero();
    C(0, 0) = e1;
    C(1, 1) = 0.9 * (1.0 - nu * (e1 - 1.0));
    Eigen::Vector3d S;
    w.calcEnergy(C, &S, nullptr);
    EXPECT_EQ(w.calcState(C), 1);
    EXPECT_NEAR(S(1), 0.0, 1e-9 * E);
    EXPECT_NEAR(S(0), E * 0.5 * (e1 - 1.0), 1e-9 * E);
}
