// The fixed-point accelerations on linear maps whose answers are known.
#include <cosim/Acceleration.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>

using namespace cosim;

namespace {

// Iterates x <- acc.next(x, H(x)) for H(x) = A x + b until |H(x) - x| < tol; returns the
// iterations (H evaluations) taken, or -1 after maxIt.
int iterate(Accelerator& acc, const Eigen::MatrixXd& A, const Eigen::VectorXd& b,
            Eigen::VectorXd& x, double tol, int maxIt) {
    acc.beginStep();
    for (int k = 1; k <= maxIt; ++k) {
        const Eigen::VectorXd Hx = A * x + b;
        if ((Hx - x).norm() < tol) {
            acc.endStep();
            return k;
        }
        x = acc.next(x, Hx);
        if (!x.allFinite()) return -1;
    }
    return -1;
}

// A map whose plain iteration diverges: eigenvalues of A from -4.5 to 0.5.
Eigen::MatrixXd divergentMap(int n) {
    Eigen::MatrixXd Q = Eigen::MatrixXd::Random(n, n);
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(Q);
    const Eigen::MatrixXd U = qr.householderQ();
    Eigen::VectorXd ev = Eigen::VectorXd::LinSpaced(n, -4.5, 0.5);
    return U * ev.asDiagonal() * U.transpose();
}

}  // namespace

TEST(Acceleration, ConstantRelaxationDivergesWhereTheMapExpandsAndConvergesWhereItContracts) {
    // Scalar H(x) = a x + b: the relaxed map's factor is 1 - w (1 - a).
    Eigen::MatrixXd A(1, 1);
    Eigen::VectorXd b(1), x(1);
    b << 1.0;
    ConstantRelaxation w(0.5);
    A << -4.5;  // factor -1.75
    x << 0.0;
    EXPECT_EQ(iterate(w, A, b, x, 1e-10, 200), -1);
    A << -0.5;  // factor 0.25
    x << 0.0;
    EXPECT_GT(iterate(w, A, b, x, 1e-10, 200), 0);
    EXPECT_NEAR(x(0), 1.0 / 1.5, 1e-10);
}

TEST(Acceleration, AitkenSolvesAScalarLinearMapInThreeEvaluations) {
    // Reference: on a scalar linear map Aitken's secant is exact, so the third evaluation of
    // H sits on the fixed point (to roundoff, tolerance 1e-12).
    Eigen::MatrixXd A(1, 1);
    A << -4.5;
    Eigen::VectorXd b(1), x(1);
    b << 2.0;
    x << 0.0;
    AitkenRelaxation aitken(0.5);
    EXPECT_EQ(iterate(aitken, A, b, x, 1e-12, 50), 3);
    EXPECT_NEAR(x(0), 2.0 / 5.5, 1e-12);
}

TEST(Acceleration, IqnIlsSolvesAnNDimensionalLinearMapInAtMostNPlusTwoEvaluations) {
    // Reference: IQN-ILS (Anderson mixing) on a linear map of dimension n reaches the fixed
    // point once its n secants span the space: at most n + 2 evaluations of H (tolerance 1e-9
    // of |b|); plain relaxation diverges on the same map.
    const int n = 6;
    std::srand(3);
    const Eigen::MatrixXd A = divergentMap(n);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0);
    const Eigen::VectorXd exact = (Eigen::MatrixXd::Identity(n, n) - A).lu().solve(b);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
    IQNILS iqn(0.5);
    const int k = iterate(iqn, A, b, x, 1e-9 * b.norm(), 50);
    EXPECT_GT(k, 0);
    EXPECT_LE(k, n + 2);
    EXPECT_LT((x - exact).norm(), 1e-8 * exact.norm());
    x.setZero();
    ConstantRelaxation w(0.5);
    EXPECT_EQ(iterate(w, A, b, x, 1e-9 * b.norm(), 200), -1);
}

TEST(Acceleration, IqnIlsReusingEarlierStepsConvergesInFewerEvaluations) {
    // The same map with another right-hand side each step (the next macro step): the secants
    // of the last step still describe the map, so with reuse the second step converges in at
    // most 3 evaluations.
    const int n = 6;
    std::srand(5);
    const Eigen::MatrixXd A = divergentMap(n);
    IQNILS fresh(0.5, 0), reuse(0.5, 2);
    Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0);
    Eigen::VectorXd x1 = Eigen::VectorXd::Zero(n), x2 = x1;
    iterate(fresh, A, b, x1, 1e-9, 50);
    iterate(reuse, A, b, x2, 1e-9, 50);
    b *= 1.1;
    const int kFresh = iterate(fresh, A, b, x1, 1e-9, 50);
    const int kReuse = iterate(reuse, A, b, x2, 1e-9, 50);
    EXPECT_GT(kReuse, 0);
    EXPECT_LE(kReuse, 3);
    EXPECT_GT(kFresh, kReuse);
}

TEST(Acceleration, OptionsOutOfRangeAreRefusedWithTheValidRange) {
    try {
        IQNILS bad(1.5);
        FAIL() << "accepted relaxation 1.5";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("valid: 0 < relaxation <= 1"), std::string::npos);
    }
    EXPECT_THROW(IQNILS(0.5, -1), std::invalid_argument);
    EXPECT_THROW(AitkenRelaxation(0.0), std::invalid_argument);
}
