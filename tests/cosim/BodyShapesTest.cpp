// The patient's contact shapes as bag shapes: the round cone against the body's own query and
// against bags' capsule, its normal derivative against finite differences, and an ellipsoid
// posed on its segment.
#include <bags/Contact.h>
#include <body/ContactShape.h>
#include <cosim/BodyParticipant.h>
#include <cosim/BodyShapes.h>
#include <gtest/gtest.h>

#include <cstdlib>

using namespace cosim;
using Vec3 = Eigen::Vector3d;

namespace {

Vec3 toEigen(const SimTK::Vec3& v) { return Vec3(v[0], v[1], v[2]); }
SimTK::Vec3 toSimTK(const Vec3& v) { return SimTK::Vec3(v.x(), v.y(), v.z()); }

// Points around a shape: within `reach` [m] of the origin, seeded.
std::vector<Vec3> samplePoints(double reach, int n, unsigned seed) {
    std::srand(seed);
    std::vector<Vec3> p;
    for (int i = 0; i < n; ++i) p.push_back(Vec3::Random() * reach);
    return p;
}

Eigen::Isometry3d somePose() {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = Eigen::AngleAxisd(0.7, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
    X.translation() = Vec3(0.3, -0.1, 0.25);
    return X;
}

}  // namespace

TEST(BodyShapes, RoundConeAgreesWithTheBodysOwnShapeAnywhere) {
    // Reference: body::ContactShape::calcSurfaceQuery (the shape the body is built with).
    // Tolerance 1e-12 m (the same closed form, evaluated in another frame).
    const body::ContactShape cone = body::ContactShape::makeRoundCone(
        SimTK::Vec3(0.01, 0.02, -0.05), 0.06, SimTK::Vec3(-0.02, 0.0, 0.30), 0.035);
    const BagShapeOfBody b = makeBagShape(cone);
    ASSERT_EQ(b.shape->getName(), "round-cone");
    const Eigen::Isometry3d X_GB = somePose();
    b.shape->setPose(X_GB * toEigen(b.X_BS));
    for (const Vec3& p_B : samplePoints(0.4, 400, 1)) {
        const body::SurfaceQuery q = cone.calcSurfaceQuery(toSimTK(p_B));
        Vec3 c, n;
        const double d = b.shape->calcSignedDistance(X_GB * p_B, &c, &n);
        EXPECT_NEAR(d, q.distance, 1e-12);
        EXPECT_LT((c - X_GB * toEigen(q.closestPoint)).norm(), 1e-12);
        EXPECT_LT((n - X_GB.linear() * toEigen(q.normal)).norm(), 1e-12);
        EXPECT_LE(b.shape->calcDistanceLowerBound(X_GB * p_B), d + 1e-12);  // a lower bound
        // and a tight one: the cone holds the capsule of the smaller radius, so the capsule
        // bound of the larger is within rA - rB of the distance (a bounding sphere is not).
        EXPECT_GE(b.shape->calcDistanceLowerBound(X_GB * p_B), d - (0.06 - 0.035) - 1e-12);
    }
}

TEST(BodyShapes, RoundConeLowerBoundReachHoldsEveryPointWithinTheBound) {
    // The larger radius at the end nearer the frame origin: there the capsule of the bound
    // reaches beyond the cone's bounding sphere (0.3 + 0.06 m against 0.33 m), and the reach
    // must hold it. Points along the axis past B and at random; bounds at -1, 0 and 3 cm.
    auto cone = makeRoundCone(Vec3(0, 0, 0), 0.06, Vec3(0, 0, 0.3), 0.03);
    cone->setPose(somePose());
    const Eigen::Isometry3d X = somePose();
    std::vector<Vec3> pts = samplePoints(0.45, 4000, 3);
    for (double z = 0.30; z < 0.45; z += 0.002) pts.push_back(Vec3(0.0, 0.0, z));
    for (double t : {-0.01, 0.0, 0.03}) {
        const double reach = cone->getLowerBoundReach(t);
        for (const Vec3& p_S : pts) {
            const Vec3 p = X * p_S;
            if (cone->calcDistanceLowerBound(p) <= t)
                EXPECT_LE(p_S.norm(), reach + 1e-12) << p_S.transpose() << " t " << t;
        }
    }
    EXPECT_NEAR(cone->getLowerBoundReach(0.0), 0.36, 1e-12);
}

TEST(BodyShapes, RoundConeNormalDerivativeMatchesFiniteDifferences) {
    // Reference: central differences of the normal, h = 1e-7 m, at points off the axis in the
    // A sphere, the cone and the B sphere regions. Tolerance 1e-6 of 1 / (distance to the axis
    // or centre), the derivative's scale.
    auto cone = makeRoundCone(Vec3(0, 0, 0), 0.05, Vec3(0, 0, 0.3), 0.03);
    cone->setPose(somePose());
    const Eigen::Isometry3d X = somePose();
    for (const Vec3& p_S : {Vec3(0.04, 0.03, -0.06), Vec3(0.07, -0.02, 0.15),
                            Vec3(-0.03, 0.05, 0.36), Vec3(0.02, 0.01, 0.1)}) {
        const Vec3 p = X * p_S;
        const Eigen::Matrix3d dn = cone->calcNormalDerivative(p);
        Eigen::Matrix3d fd;
        const double h = 1e-7;
        for (int j = 0; j < 3; ++j) {
            Vec3 np, nm;
            cone->calcSignedDistance(p + h * Vec3::Unit(j), nullptr, &np);
            cone->calcSignedDistance(p - h * Vec3::Unit(j), nullptr, &nm);
            fd.col(j) = (np - nm) / (2 * h);
        }
        EXPECT_LT((dn - fd).cwiseAbs().maxCoeff(), 1e-6 * fd.cwiseAbs().maxCoeff())
            << "at " << p_S.transpose() << "\n"
            << dn << "\n"
            << fd;
        EXPECT_GT(fd.cwiseAbs().maxCoeff(), 1.0);  // curved there: the check has teeth
    }
}

TEST(BodyShapes, RoundConeOfEqualRadiiIsBagsCapsule) {
    // Reference: bags::makeCapsule (radius 0.04 m, half-length 0.12 m along z). Tolerance
    // 1e-12 for distance, closest point, normal and normal derivative.
    auto cone = makeRoundCone(Vec3(0, 0, -0.12), 0.04, Vec3(0, 0, 0.12), 0.04);
    auto capsule = bags::makeCapsule(0.04, 0.12);
    cone->setPose(somePose());
    capsule->setPose(somePose());
    for (const Vec3& p : samplePoints(0.3, 300, 2)) {
        const Vec3 q = somePose() * p;
        double d1, d2;
        Vec3 c1, c2, n1, n2;
        Eigen::Matrix3d dn1, dn2;
        cone->calcContactGeometry(q, &d1, &c1, &n1, &dn1);
        capsule->calcContactGeometry(q, &d2, &c2, &n2, &dn2);
        EXPECT_NEAR(d1, d2, 1e-12);
        EXPECT_LT((c1 - c2).norm(), 1e-12);
        EXPECT_LT((n1 - n2).norm(), 1e-12);
        EXPECT_LT((dn1 - dn2).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, dn2.norm()));
    }
}

TEST(BodyShapes, EllipsoidPosedOnItsSegmentAgreesWithTheBodysOwnShape) {
    // Reference: body::ContactShape::calcSurfaceQuery of an ellipsoid turned and offset on its
    // segment. Tolerance 1e-9 m (both find the closest point iteratively).
    const body::ContactShape e = body::ContactShape::makeEllipsoid(
        SimTK::Vec3(0.12, 0.08, 0.05), SimTK::Vec3(0.02, -0.01, 0.1),
        SimTK::Rotation(0.4, SimTK::ZAxis) * SimTK::Rotation(-0.2, SimTK::XAxis));
    const BagShapeOfBody b = makeBagShape(e);
    const Eigen::Isometry3d X_GB = somePose();
    b.shape->setPose(X_GB * toEigen(b.X_BS));
    for (const Vec3& p_B : samplePoints(0.3, 300, 3)) {
        const body::SurfaceQuery q = e.calcSurfaceQuery(toSimTK(p_B));
        Vec3 c, n;
        const double d = b.shape->calcSignedDistance(X_GB * p_B, &c, &n);
        EXPECT_NEAR(d, q.distance, 1e-9);
        EXPECT_LT((n - X_GB.linear() * toEigen(q.normal)).norm(), 1e-7);
    }
}

TEST(BodyShapes, RoundConesThatCannotBeBuiltAreRefused) {
    EXPECT_THROW(makeRoundCone(Vec3::Zero(), 0.05, Vec3(0, 0, 0.01), 0.02),
                 std::invalid_argument);  // one sphere inside the other
    EXPECT_THROW(makeRoundCone(Vec3::Zero(), 0.0, Vec3(0, 0, 0.3), 0.02), std::invalid_argument);
}
