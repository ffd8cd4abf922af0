// Analytic surface queries of ellipsoids and round cones against brute force and finite
// differences.
#include <body/ContactShape.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using body::ContactShape;

// Smallest distance from p to a dense sampling of the shape's surface [m].
double bruteForceDistance(const std::vector<body::SurfaceSample>& s, const SimTK::Vec3& p) {
    double d = SimTK::Infinity;
    for (const auto& x : s) d = std::min(d, (x.p_B - p).norm());
    return d;
}

SimTK::Vec3 randomPoint(std::mt19937& rng, double scale) {
    std::uniform_real_distribution<double> u(-scale, scale);
    return SimTK::Vec3(u(rng), u(rng), u(rng));
}

std::vector<ContactShape> makeShapes() {
    return {
        ContactShape::makeEllipsoid(SimTK::Vec3(0.09, 0.14, 0.22), SimTK::Vec3(0.01, 0.02, -0.03),
                                    SimTK::Rotation(0.4, SimTK::UnitVec3(1, 2, 3))),
        ContactShape::makeEllipsoid(SimTK::Vec3(0.05, 0.05, 0.05), SimTK::Vec3(0)),
        ContactShape::makeRoundCone(SimTK::Vec3(0, 0, 0), 0.11, SimTK::Vec3(0.05, -0.4, 0.02),
                                    0.06),
        ContactShape::makeRoundCone(SimTK::Vec3(0, 0, 0), 0.04, SimTK::Vec3(0, -0.28, 0), 0.04)};
}

}  // namespace

TEST(ContactShape, ClosestPointIsOnSurfaceAlongNormalAndNearest) {
    std::mt19937 rng(7);
    for (const ContactShape& shape : makeShapes()) {
        const auto dense = shape.calcSurfaceSamples(0.002);
        for (int k = 0; k < 200; ++k) {
            const SimTK::Vec3 p =
                shape.getBoundingCentre() + randomPoint(rng, 1.3 * shape.getBoundingRadius());
            const body::SurfaceQuery q = shape.calcSurfaceQuery(p);
            // The closest point lies on the surface: its own distance is zero (1e-10 m).
            EXPECT_NEAR(shape.calcSignedDistance(q.closestPoint), 0.0, 1e-10);
            // p = x + d n (1e-10 m), with a unit normal.
            EXPECT_NEAR((p - (q.closestPoint + q.distance * q.normal)).norm(), 0.0, 1e-10);
            EXPECT_NEAR(q.normal.norm(), 1.0, 1e-12);
            // |d| equals the brute-force nearest distance over a 2 mm sampling, which can only
            // overestimate it, by at most about half the sampling spacing.
            const double bf = bruteForceDistance(dense, p);
            EXPECT_LE(std::abs(q.distance), bf + 1e-12);
            EXPECT_GE(std::abs(q.distance), bf - 1.5e-3);
        }
    }
}

TEST(ContactShape, SignedDistanceGradientIsTheNormal) {
    std::mt19937 rng(11);
    const double h = 1e-6;  // central differences: error O(h^2 * curvature) ~ 1e-9
    for (const ContactShape& shape : makeShapes()) {
        int checked = 0;
        for (int k = 0; k < 200 && checked < 60; ++k) {
            const SimTK::Vec3 p =
                shape.getBoundingCentre() + randomPoint(rng, 1.3 * shape.getBoundingRadius());
            const body::SurfaceQuery q = shape.calcSurfaceQuery(p);
            if (q.distance < -0.01) continue;  // stay clear of the medial surface inside
            SimTK::Vec3 g;
            for (int i = 0; i < 3; ++i) {
                SimTK::Vec3 dp(0);
                dp[i] = h;
                g[i] =
                    (shape.calcSignedDistance(p + dp) - shape.calcSignedDistance(p - dp)) / (2 * h);
            }
            EXPECT_NEAR((g - q.normal).norm(), 0.0, 1e-6);
            ++checked;
        }
        EXPECT_GT(checked, 30);
    }
}

TEST(ContactShape, SphereAndCapsuleMatchClosedForms) {
    const ContactShape sphere =
        ContactShape::makeEllipsoid(SimTK::Vec3(0.05), SimTK::Vec3(0.1, 0, 0));
    EXPECT_NEAR(sphere.calcSignedDistance(SimTK::Vec3(0.1, 0.3, 0.4)), 0.5 - 0.05, 1e-14);
    EXPECT_NEAR(sphere.calcSignedDistance(SimTK::Vec3(0.12, 0, 0)), 0.02 - 0.05, 1e-14);
    // Capsule: distance to the axis segment minus the radius.
    const ContactShape cap =
        ContactShape::makeRoundCone(SimTK::Vec3(0), 0.04, SimTK::Vec3(0, -0.3, 0), 0.04);
    EXPECT_NEAR(cap.calcSignedDistance(SimTK::Vec3(0.1, -0.1, 0)), 0.1 - 0.04, 1e-14);
    EXPECT_NEAR(cap.calcSignedDistance(SimTK::Vec3(0, -0.4, 0)), 0.1 - 0.04, 1e-14);
    EXPECT_NEAR(cap.calcSignedDistance(SimTK::Vec3(0.01, -0.2, 0)), 0.01 - 0.04, 1e-14);
    EXPECT_NEAR(cap.calcSurfaceArea(), 4 * SimTK::Pi * 0.04 * 0.04 + 2 * SimTK::Pi * 0.04 * 0.3,
                1e-14);
}

TEST(ContactShape, SupportPointIsTheFurthestSurfacePoint) {
    std::mt19937 rng(3);
    for (const ContactShape& shape : makeShapes()) {
        const auto dense = shape.calcSurfaceSamples(0.003);
        for (int k = 0; k < 20; ++k) {
            SimTK::Vec3 d = randomPoint(rng, 1.0);
            d /= d.norm();
            const SimTK::Vec3 s = shape.calcSupportPoint(d);
            EXPECT_NEAR(shape.calcSignedDistance(s), 0.0, 1e-10);  // on the surface
            double best = -SimTK::Infinity;
            for (const auto& x : dense) best = std::max(best, ~x.p_B * d);
            EXPECT_GE(~s * d, best - 1e-12);  // no sample goes further
            EXPECT_LE(~s * d, best + 3e-3);   // within the sampling spacing
        }
    }
}

TEST(ContactShape, SamplePatchesCoverTheSurfaceArea) {
    for (const ContactShape& shape : makeShapes()) {
        const auto samples = shape.calcSurfaceSamples(0.005);
        double area = 0;
        for (const auto& s : samples) {
            area += s.area;
            EXPECT_NEAR(shape.calcSignedDistance(s.p_B), 0.0, 1e-10);
            EXPECT_NEAR((s.n_B - shape.calcSurfaceQuery(s.p_B).normal).norm(), 0.0, 1e-8);
        }
        // Round cone: exact formula; ellipsoid: Thomsen's approximation is good to ~1 %; the
        // cap selection on a Fibonacci lattice leaves up to ~1 % of a cap's area.
        EXPECT_NEAR(area / shape.calcSurfaceArea(), 1.0, 0.015);
    }
}

TEST(ContactShape, VolumeMatchesMonteCarloOfInsideTest) {
    std::mt19937 rng(5);
    for (const ContactShape& shape : makeShapes()) {
        const double R = shape.getBoundingRadius();
        const int n = 100000;
        int inside = 0;
        for (int k = 0; k < n; ++k)
            if (shape.calcSignedDistance(shape.getBoundingCentre() + randomPoint(rng, R)) < 0)
                ++inside;
        const double frac = static_cast<double>(inside) / n;
        const double v = frac * std::pow(2 * R, 3);
        const double sigma = std::sqrt(frac * (1 - frac) / n) * std::pow(2 * R, 3);
        EXPECT_NEAR(v, shape.calcVolume(), 4 * sigma);  // 4 standard errors
    }
}

TEST(ContactShape, RejectsDegenerateShapes) {
    EXPECT_THROW(ContactShape::makeEllipsoid(SimTK::Vec3(0.1, 0, 0.1), SimTK::Vec3(0)),
                 std::invalid_argument);
    EXPECT_THROW(ContactShape::makeRoundCone(SimTK::Vec3(0), 0.1, SimTK::Vec3(0, 0.05, 0), 0.02),
                 std::invalid_argument);
}
