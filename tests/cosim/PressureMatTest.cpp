// The virtual pressure mat: nodal contact forces gathered onto sensels, force conserved.
#include <cosim/PressureMat.h>
#include <gtest/gtest.h>

#include <cstdlib>

using namespace cosim;

namespace {

PressureMatOptions smallMat() {
    PressureMatOptions o;
    o.rows = 8;
    o.columns = 4;
    o.origin = Eigen::Vector2d(-0.4, -0.1);
    o.size = Eigen::Vector2d(0.8, 0.2);  // 100 x 50 mm sensels
    return o;
}

}  // namespace

TEST(PressureMat, ConservesTheForceOfTheNodesOnItAndCountsTheRestOff) {
    // Reference: the sum of p_i A_i over 2000 random nodes, inside and beyond the mat.
    // Tolerance 1e-12 relative (the bilinear weights sum to one).
    std::srand(7);
    const int n = 2000;
    Eigen::Matrix3Xd x = Eigen::Matrix3Xd::Random(3, n);
    x.row(0) *= 0.5;   // some beyond |x| = 0.4
    x.row(1) *= 0.12;  // some beyond |y| = 0.1
    const Eigen::VectorXd p = (Eigen::VectorXd::Random(n).array() + 1.0) * 5e3;
    const Eigen::VectorXd A = (Eigen::VectorXd::Random(n).array() + 1.5) * 1e-4;
    double on = 0.0, off = 0.0;
    for (int i = 0; i < n; ++i)
        (std::abs(x(0, i)) <= 0.4 && std::abs(x(1, i)) <= 0.1 ? on : off) += p(i) * A(i);
    ASSERT_GT(off, 0.0);
    PressureMat mat(smallMat());
    mat.addNodalPressures(x, p, A);
    EXPECT_NEAR(mat.calcTotalForce(), on, 1e-12 * on);
    EXPECT_NEAR(mat.getOffMatForce(), off, 1e-12 * off);
    mat.clear();
    EXPECT_EQ(mat.calcTotalForce(), 0.0);
    EXPECT_EQ(mat.getOffMatForce(), 0.0);
}

TEST(PressureMat, PutsANodeOnASenselCentreInThatSenselAndSplitsOneBetweenCentresEvenly) {
    PressureMat mat(smallMat());
    const double area = mat.getSenselArea();
    EXPECT_NEAR(area, 0.1 * 0.05, 1e-15);
    Eigen::Matrix3Xd x(3, 1);
    Eigen::VectorXd p(1), A(1);
    p << 1000.0;
    A << 1e-4;                                             // 0.1 N
    x.col(0) << -0.4 + 2.5 * 0.1, -0.1 + 1.5 * 0.05, 0.0;  // centre of sensel (2, 1)
    mat.addNodalPressures(x, p, A);
    EXPECT_NEAR(mat.getPressure()(2, 1), 0.1 / area, 1e-9);
    EXPECT_NEAR(mat.getPressure().sum(), 0.1 / area, 1e-9);
    mat.clear();
    x.col(0) << -0.4 + 3.0 * 0.1, -0.1 + 1.5 * 0.05, 0.0;  // between sensels (2, 1) and (3, 1)
    mat.addNodalPressures(x, p, A);
    EXPECT_NEAR(mat.getPressure()(2, 1), 0.05 / area, 1e-9);
    EXPECT_NEAR(mat.getPressure()(3, 1), 0.05 / area, 1e-9);
    mat.clear();
    x.col(0) << -0.4 + 0.01, 0.1 - 0.01, 0.0;  // in the corner, beyond the outer centres
    mat.addNodalPressures(x, p, A);
    EXPECT_NEAR(mat.getPressure()(0, 3), 0.1 / area, 1e-9);
}

TEST(PressureMat, BadOptionsAndSizesAreRefused) {
    PressureMatOptions o = smallMat();
    o.size.x() = 0.0;
    EXPECT_THROW(o.validate(), std::invalid_argument);
    PressureMat mat(smallMat());
    EXPECT_THROW(mat.addNodalPressures(Eigen::Matrix3Xd::Zero(3, 2), Eigen::VectorXd::Zero(1),
                                       Eigen::VectorXd::Zero(2)),
                 std::invalid_argument);
}
