// Tests of bags::Mesh: areas, validation, chamber volume and its derivatives.

#include <bags/Geometry.h>
#include <bags/Mesh.h>
#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <cmath>
#include <random>

using namespace bags;

namespace {

/// Reference positions moved by a random displacement of up to `amp` per coordinate.
Eigen::Matrix3Xd perturbed(const Mesh& mesh, double amp, unsigned seed) {
    std::mt19937 gen(seed);
    std::uniform_real_distribution<double> u(-amp, amp);
    Eigen::Matrix3Xd x = mesh.X;
    for (int n = 0; n < x.cols(); ++n)
        for (int d = 0; d < 3; ++d) x(d, n) += u(gen);
    return x;
}

Eigen::MatrixXd denseHessian(const EnergyAccumulator& acc, int ndof) {
    Eigen::SparseMatrix<double> H(ndof, ndof);
    H.setFromTriplets(acc.hess.begin(), acc.hess.end());
    return Eigen::MatrixXd(H);
}

}  // namespace

TEST(Mesh, AreasSumToPanelAreasOfBox) {
    const Mesh m = makeBoxBag(0.3, 0.2, 0.1, 0.05);
    // Reference: surface of a 0.3 x 0.2 x 0.1 box = 2 (0.06 + 0.03 + 0.02) = 0.22 m^2;
    // tolerance 1e-14 relative (rounding only).
    EXPECT_NEAR(m.calcTriangleAreas().sum(), 0.22, 1e-14 * 0.22);
    EXPECT_NEAR(m.calcNodalAreas().sum(), 0.22, 1e-14 * 0.22);
    EXPECT_GT(m.calcNodalAreas().minCoeff(), 0.0);
}

TEST(Mesh, BoxVolumeIsExactAndTranslationInvariant) {
    const Mesh m = makeBoxBag(0.35, 0.1, 0.15, 0.01);
    ASSERT_NO_THROW(m.validate());
    // Reference: 0.35 * 0.1 * 0.15 = 5.25e-3 m^3 (flat faces: the formula is exact);
    // tolerance 1e-13 relative.
    const double V = calcChamberVolume(m, 0, m.X);
    EXPECT_NEAR(V, 5.25e-3, 1e-13 * 5.25e-3);
    Eigen::Matrix3Xd x = m.X;
    x.colwise() += Vec3(1.7, -2.3, 0.9);  // far from the origin
    EXPECT_NEAR(calcChamberVolume(m, 0, x), 5.25e-3, 1e-11 * 5.25e-3);
}

TEST(Mesh, VolumeGradientMatchesCentralDifferences) {
    DoubleWedgeParams p;
    p.meshSize = 0.05;
    const Mesh m = makeDoubleWedgeBag(p);
    const Eigen::Matrix3Xd x = perturbed(m, 0.01, 7);
    for (int c = 0; c < static_cast<int>(m.chambers.size()); ++c) {
        const Eigen::VectorXd g = calcChamberVolumeGradient(m, c, x);
        const double h = 1e-6;
        double err = 0.0;
        for (int i = 0; i < 3 * m.getNumNodes(); ++i) {
            Eigen::Matrix3Xd xp = x, xm = x;
            xp(i % 3, i / 3) += h;
            xm(i % 3, i / 3) -= h;
            const double fd = (calcChamberVolume(m, c, xp) - calcChamberVolume(m, c, xm)) / (2 * h);
            err = std::max(err, std::abs(fd - g[i]));
        }
        // V is linear in each coordinate, so central differences are exact up to rounding:
        // |V| ~ 1e-3 m^3, eps/h ~ 1e-16 * 1e-3 / 1e-6 = 1e-13; tolerance 1e-9 of max|g|.
        EXPECT_LT(err, 1e-9 * g.cwiseAbs().maxCoeff()) << "chamber " << c;
        // Closed chamber: a rigid translation keeps V, so the gradient's x, y, z sums vanish.
        Vec3 sum = Vec3::Zero();
        for (int n = 0; n < m.getNumNodes(); ++n) sum += g.segment<3>(3 * n);
        EXPECT_LT(sum.norm(), 1e-12 * g.cwiseAbs().maxCoeff()) << "chamber " << c;
    }
}

TEST(Mesh, VolumeHessianMatchesCentralDifferencesOfGradient) {
    DoubleWedgeParams p;
    p.meshSize = 0.05;
    const Mesh m = makeDoubleWedgeBag(p);
    const Eigen::Matrix3Xd x = perturbed(m, 0.01, 11);
    const int ndof = 3 * m.getNumNodes();
    const double scale = -2.5;  // as a gas term calls it with -p
    for (int c = 0; c < static_cast<int>(m.chambers.size()); ++c) {
        EnergyAccumulator acc(m.getNumNodes());
        const double V = calcChamberVolume(m, c, x, &acc, scale);
        EXPECT_DOUBLE_EQ(acc.energy, scale * V);
        EXPECT_LT((acc.grad - scale * calcChamberVolumeGradient(m, c, x)).norm(),
                  1e-14 * acc.grad.norm());
        const Eigen::MatrixXd H = denseHessian(acc, ndof);
        const double h = 1e-6;
        Eigen::MatrixXd Hfd(ndof, ndof);
        for (int j = 0; j < ndof; ++j) {
            Eigen::Matrix3Xd xp = x, xm = x;
            xp(j % 3, j / 3) += h;
            xm(j % 3, j / 3) -= h;
            Hfd.col(j) =
                scale *
                (calcChamberVolumeGradient(m, c, xp) - calcChamberVolumeGradient(m, c, xm)) /
                (2 * h);
        }
        // dV/dx is linear in each coordinate: central differences exact up to rounding;
        // tolerance 1e-8 of the largest entry.
        const double maxH = H.cwiseAbs().maxCoeff();
        EXPECT_GT(maxH, 0.0);
        EXPECT_LT((H - Hfd).cwiseAbs().maxCoeff(), 1e-8 * maxH) << "chamber " << c;
        // The volume Hessian is symmetric.
        EXPECT_LT((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-14 * maxH);
    }
}

TEST(Mesh, AccumulatorFlagsSkipGradientAndHessian) {
    const Mesh m = makeBoxBag(0.1, 0.1, 0.1, 0.05);
    EnergyAccumulator acc(m.getNumNodes());
    acc.wantGradient = false;
    acc.wantHessian = false;
    const double V = calcChamberVolume(m, 0, m.X, &acc, 3.0);
    // Reference: 1e-3 m^3 box, energy = 3 V; nothing else touched.
    EXPECT_NEAR(V, 1e-3, 1e-15);
    EXPECT_NEAR(acc.energy, 3e-3, 1e-15);
    EXPECT_EQ(acc.grad.norm(), 0.0);
    EXPECT_TRUE(acc.hess.empty());
}

TEST(Mesh, AddVolumeGradientAccumulatesScaled) {
    const Mesh m = makeBoxBag(0.2, 0.1, 0.1, 0.05);
    const Eigen::Matrix3Xd x = perturbed(m, 0.005, 3);
    Eigen::VectorXd g = Eigen::VectorXd::Ones(3 * m.getNumNodes());
    const double V = addChamberVolumeGradient(m, 0, x, g, 2.0);
    EXPECT_DOUBLE_EQ(V, calcChamberVolume(m, 0, x));
    const Eigen::VectorXd ref =
        Eigen::VectorXd::Ones(3 * m.getNumNodes()) + 2.0 * calcChamberVolumeGradient(m, 0, x);
    EXPECT_LT((g - ref).norm(), 1e-15 * ref.norm());
}

TEST(Mesh, ValidateAcceptsGeneratedMeshes) {
    EXPECT_NO_THROW(makeBoxBag(0.3, 0.2, 0.1, 0.02).validate());
    EXPECT_NO_THROW(makeSphere(1.0, 2).validate());
    EXPECT_NO_THROW(makeSquareCushion(0.8485, 8, 0.01).validate());
    EXPECT_NO_THROW(makeDisk(0.1, 5).validate());
    EXPECT_NO_THROW(makeDoubleWedgeBag(DoubleWedgeParams{}).validate());
}

TEST(Mesh, ValidateRejectsOpenChamber) {
    Mesh m = makeBoxBag(0.2, 0.1, 0.1, 0.05, false);
    m.chambers[0].tris.pop_back();
    m.chambers[0].signs.pop_back();
    EXPECT_THROW(m.validate(), std::invalid_argument);
}

TEST(Mesh, ValidateRejectsMisorientedTriangle) {
    Mesh m = makeBoxBag(0.2, 0.1, 0.1, 0.05, false);
    std::swap(m.tris(1, 3), m.tris(2, 3));  // one triangle's normal now points inwards
    try {
        m.validate();
        FAIL() << "misoriented triangle not detected";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("misoriented"), std::string::npos) << e.what();
    }
}

TEST(Mesh, ValidateRejectsWrongSign) {
    Mesh m = makeSphere(1.0, 1);
    m.chambers[0].signs[5] = -1;
    EXPECT_THROW(m.validate(), std::invalid_argument);
    m.chambers[0].signs[5] = 2;
    EXPECT_THROW(m.validate(), std::invalid_argument);
}

TEST(Mesh, ValidateRejectsDiaphragmWithSameSignInBothChambers) {
    Mesh m = makeDoubleWedgeBag(DoubleWedgeParams{});
    ChamberBoundary& g = m.chambers[m.findChamber("wedge-gentle")];
    const int dia = m.findPanel("diaphragm");
    for (size_t i = 0; i < g.tris.size(); ++i)
        if (m.triPanel[g.tris[i]] == dia) g.signs[i] = 1;
    EXPECT_THROW(m.validate(), std::invalid_argument);
}

TEST(Mesh, ValidateAllowsOpenChamberOnlyWithSupportedRim) {
    Mesh m = makeDisk(0.1, 4);
    EXPECT_NO_THROW(m.validate());
    m.supportNodes.pop_back();  // one rim node free
    EXPECT_THROW(m.validate(), std::invalid_argument);
}

TEST(Mesh, ValidateRejectsBadIndices) {
    Mesh m = makeSphere(1.0, 0);
    Mesh bad = m;
    bad.tris(0, 0) = bad.getNumNodes();
    EXPECT_THROW(bad.validate(), std::invalid_argument);
    bad = m;
    bad.chambers[0].tris[0] = -1;
    EXPECT_THROW(bad.validate(), std::invalid_argument);
    bad = m;
    bad.supportNodes = {bad.getNumNodes()};
    EXPECT_THROW(bad.validate(), std::invalid_argument);
    bad = m;
    bad.triPanel.pop_back();
    EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(Mesh, OpenDiskVolumeMeasuresSweptVolume) {
    const double R = 0.1, h = 0.01;
    const Mesh m = makeDisk(R, 24);
    EXPECT_NEAR(calcChamberVolume(m, 0, m.X), 0.0, 1e-18);  // flat: nothing swept
    // Lift into the paraboloid z = h (1 - r^2/R^2): analytic volume pi R^2 h / 2.
    Eigen::Matrix3Xd x = m.X;
    for (int n = 0; n < x.cols(); ++n) {
        const double r2 = x(0, n) * x(0, n) + x(1, n) * x(1, n);
        x(2, n) = h * (1.0 - r2 / (R * R));
    }
    const double ref = 0.5 * M_PI * R * R * h;
    // Tolerance 1 %: polygonal rim (inscribed 144-gon, area deficit 0.03 %) and the
    // piecewise-linear interpolation of the paraboloid (O(h^2), about 0.2 % at 24 rings).
    EXPECT_NEAR(calcChamberVolume(m, 0, x), ref, 0.01 * ref);
    // With the rim fixed, volume changes do not depend on the origin: translating both the
    // flat and the lifted state by t keeps V(x) - V(X) (each alone shifts by t . A_rim / 3).
    const Vec3 t(0.3, 0.2, -0.5);
    Eigen::Matrix3Xd y = x, Y = m.X;
    y.colwise() += t;
    Y.colwise() += t;
    const double shifted = calcChamberVolume(m, 0, y) - calcChamberVolume(m, 0, Y);
    EXPECT_NEAR(shifted, calcChamberVolume(m, 0, x), 1e-12);  // rounding of ~1e-2 m^3 terms
    EXPECT_GT(std::abs(calcChamberVolume(m, 0, Y)), 1e-3);    // each alone does shift
}

TEST(Mesh, FindPanelAndChamberByName) {
    const Mesh m = makeDoubleWedgeBag(DoubleWedgeParams{});
    EXPECT_GE(m.findPanel("base"), 0);
    EXPECT_GE(m.findPanel("diaphragm"), 0);
    EXPECT_EQ(m.findPanel("roof"), -1);
    EXPECT_EQ(m.findChamber("wedge-steep"), 0);
    EXPECT_EQ(m.findChamber("wedge-gentle"), 1);
    EXPECT_EQ(m.findChamber("bag"), -1);
}
