// de Leva (1996) scaling: masses, centres of mass, inertias, and the BMI-dependent build.
#include <body/Anthropometry.h>
#include <body/ContactShape.h>
#include <gtest/gtest.h>

#include <cmath>

namespace {

using body::Segment;
using body::Sex;

// de Leva (1996) Table 4, typed independently of body/src/Anthropometry.cpp and cross-checked
// against R. Gurchiek's deleva.m lookup table (2018): length [mm], mass [%], CoM from the
// proximal landmark [%], radii of gyration sagittal / transverse / longitudinal [%].
struct Row {
    Segment seg;
    double len, mass, com, rs, rt, rl;
};
const Row kMale[] = {
    {Segment::Head, 203.3, 6.94, 59.76, 36.2, 37.6, 31.2},
    {Segment::UpperTrunk, 170.7, 15.96, 29.99, 71.6, 45.4, 65.9},
    {Segment::MiddleTrunk, 215.5, 16.33, 45.02, 48.2, 38.3, 46.8},
    {Segment::LowerTrunk, 145.7, 11.17, 61.15, 61.5, 55.1, 58.7},
    {Segment::UpperArmR, 281.7, 2.71, 57.72, 28.5, 26.9, 15.8},
    {Segment::ForearmL, 268.9, 1.62, 45.74, 27.6, 26.5, 12.1},
    {Segment::HandR, 86.2, 0.61, 79.00, 62.8, 51.3, 40.1},
    {Segment::ThighL, 422.2, 14.16, 40.95, 32.9, 32.9, 14.9},
    {Segment::ShankR, 434.0, 4.33, 44.59, 25.5, 24.9, 10.3},
    {Segment::FootL, 258.1, 1.37, 44.15, 25.7, 24.5, 12.4},
};
const Row kFemale[] = {
    {Segment::Head, 200.2, 6.68, 58.94, 33.0, 35.9, 31.8},
    {Segment::UpperTrunk, 142.5, 15.45, 20.77, 74.6, 50.2, 71.8},
    {Segment::MiddleTrunk, 205.3, 14.65, 45.12, 43.3, 35.4, 41.5},
    {Segment::LowerTrunk, 181.5, 12.47, 49.20, 43.3, 40.2, 44.4},
    {Segment::UpperArmL, 275.1, 2.55, 57.54, 27.8, 26.0, 14.8},
    {Segment::ForearmR, 264.3, 1.38, 45.59, 26.1, 25.7, 9.4},
    {Segment::HandL, 78.0, 0.56, 74.74, 53.1, 45.4, 33.5},
    {Segment::ThighR, 368.5, 14.78, 36.12, 36.9, 36.4, 16.2},
    {Segment::ShankL, 432.3, 4.81, 44.16, 27.1, 26.7, 9.3},
    {Segment::FootR, 228.3, 1.29, 40.14, 29.9, 27.9, 13.9},
};

// Distance of the CoM from the segment's proximal landmark along its length [m]: limbs hang
// from their origin (-Y), trunk parts have the proximal (superior) landmark at +L, the head's
// vertex is VERT-CERV (242.9 mm male, 243.7 mm female, de Leva Table 4) above its origin, and
// the foot's heel is at the back of the heel sphere.
double comFromProximal(const body::SegmentParameters& p, Sex sex, double scale) {
    switch (body::getSegmentType(p.segment)) {
        case body::SegmentType::Head:
            return (sex == Sex::Male ? 0.2429 : 0.2437) * scale - p.p_BC[1];
        case body::SegmentType::UpperTrunk:
        case body::SegmentType::MiddleTrunk:
        case body::SegmentType::LowerTrunk:
            return p.length - p.p_BC[1];
        case body::SegmentType::Foot:
            return p.p_BC[0] + p.shape.radiusA;
        default:
            return -p.p_BC[1];
    }
}

void checkReference(Sex sex, const Row* rows, int n, double height, double mass,
                    double fractionSum) {
    const body::Anthropometry a = body::calcAnthropometry(sex, height, mass);
    for (int i = 0; i < n; ++i) {
        const Row& r = rows[i];
        const body::SegmentParameters& p = a.get(r.seg);
        SCOPED_TRACE(body::getSegmentName(r.seg));
        const double L = r.len / 1000;
        const double m = r.mass / 100 * mass / fractionSum;
        // Reference subject: table values exactly (1e-12 relative: arithmetic only).
        EXPECT_NEAR(p.length, L, 1e-12);
        EXPECT_NEAR(p.mass, m, 1e-12 * m);
        EXPECT_NEAR(comFromProximal(p, sex, 1.0), r.com / 100 * L, 1e-12);
        // Body X antero-posterior, Y longitudinal, Z medio-lateral; the foot's long axis is X.
        SimTK::Vec3 k(r.rs, r.rl, r.rt);
        if (r.seg == Segment::FootL || r.seg == Segment::FootR) k = SimTK::Vec3(r.rl, r.rt, r.rs);
        for (int ax = 0; ax < 3; ++ax) {
            const double I = m * std::pow(k[ax] / 100 * L, 2);
            EXPECT_NEAR(p.inertiaC[ax], I, 1e-12 * I) << "axis " << ax;
        }
    }
}

}  // namespace

TEST(Anthropometry, ReferenceMaleMatchesDeLevaTable4) {
    // Male mass fractions sum to 100.00 %: masses are the table's fractions of 73.0 kg.
    checkReference(Sex::Male, kMale, 10, 1.741, 73.0, 1.0000);
}

TEST(Anthropometry, ReferenceFemaleMatchesDeLevaTable4) {
    // Female fractions sum to 99.99 % (rounding in the table); the model divides by the sum so
    // the total is the input.
    checkReference(Sex::Female, kFemale, 10, 1.735, 61.9, 0.9999);
}

TEST(Anthropometry, TotalMassEqualsInputForEveryBuild) {
    for (Sex sex : {Sex::Female, Sex::Male})
        for (double h : {1.4, 1.62, 1.75, 2.1})
            for (double bmi : {14.0, 22.0, 35.0, 50.0}) {
                const double m = bmi * h * h;
                const body::Anthropometry a = body::calcAnthropometry(sex, h, m);
                double sum = 0;
                for (const auto& p : a.segments) sum += p.mass;
                EXPECT_NEAR(sum, m, 1e-12 * m);  // exact up to round-off
            }
}

TEST(Anthropometry, InertiasArePositiveDefiniteAndTriangleValid) {
    for (Sex sex : {Sex::Female, Sex::Male})
        for (double h : {1.4, 1.75, 2.1}) {
            const body::Anthropometry a = body::calcAnthropometry(sex, h, 22 * h * h);
            for (const auto& p : a.segments) {
                const SimTK::Vec3& I = p.inertiaC;
                SCOPED_TRACE(body::getSegmentName(p.segment));
                for (int i = 0; i < 3; ++i) EXPECT_GT(I[i], 0);
                // Principal moments of a real body: each at most the sum of the other two.
                EXPECT_LE(I[0], I[1] + I[2]);
                EXPECT_LE(I[1], I[0] + I[2]);
                EXPECT_LE(I[2], I[0] + I[1]);
                // Simbody's own check of a physically valid inertia (throws if not).
                EXPECT_NO_THROW(SimTK::Inertia(I[0], I[1], I[2]));
            }
        }
}

TEST(Anthropometry, LengthsScaleWithHeightAndMassesWithMass) {
    const body::Anthropometry a = body::calcAnthropometry(Sex::Male, 1.741, 73.0);
    const body::Anthropometry b = body::calcAnthropometry(Sex::Male, 1.90, 90.0);
    for (int i = 0; i < body::kSegmentCount; ++i) {
        EXPECT_NEAR(b.segments[i].length / a.segments[i].length, 1.90 / 1.741, 1e-12);
        EXPECT_NEAR(b.segments[i].mass / a.segments[i].mass, 90.0 / 73.0, 1e-12);
    }
}

TEST(Anthropometry, HeavierPatientOfSameHeightIsWiderAndDeeper) {
    const body::Anthropometry slim = body::calcAnthropometry(Sex::Female, 1.65, 18.0 * 1.65 * 1.65);
    const body::Anthropometry heavy =
        body::calcAnthropometry(Sex::Female, 1.65, 35.0 * 1.65 * 1.65);
    const body::BodyBuild& s = slim.build;
    const body::BodyBuild& h = heavy.build;
    // Soft-tissue breadths and depths grow as sqrt(mass) at a fixed height: sqrt(35/18) = 1.394.
    const double f = std::sqrt(35.0 / 18.0);
    EXPECT_NEAR(h.chestBreadth / s.chestBreadth, f, 1e-9);
    EXPECT_NEAR(h.waistDepth / s.waistDepth, f, 1e-9);
    EXPECT_NEAR(h.pelvisDepth / s.pelvisDepth, f, 1e-9);
    EXPECT_NEAR(h.buttockDepth / s.buttockDepth, f, 1e-9);
    EXPECT_GT(h.hipBreadth, s.hipBreadth + 0.03);  // hip breadth = joint separation + 2 r
    // Skeleton and skull do not change with BMI.
    EXPECT_DOUBLE_EQ(h.shoulderJointSeparation, s.shoulderJointSeparation);
    EXPECT_DOUBLE_EQ(h.hipJointSeparation, s.hipJointSeparation);
    EXPECT_DOUBLE_EQ(h.headBreadth, s.headBreadth);
    EXPECT_DOUBLE_EQ(h.modelStature, s.modelStature);
}

TEST(Anthropometry, ShapesHoldTheSegmentMassAtTissueDensity) {
    const body::Anthropometry a = body::calcAnthropometry(Sex::Male, 1.80, 85.0);
    for (Segment seg :
         {Segment::UpperTrunk, Segment::MiddleTrunk, Segment::LowerTrunk, Segment::HandR}) {
        const body::SegmentParameters& p = a.get(seg);
        const SimTK::Vec3& ax = p.shape.semiAxes;
        const double volume = 4.0 / 3.0 * SimTK::Pi * ax[0] * ax[1] * ax[2];
        const double rho = body::getSegmentDensity(body::getSegmentType(seg));
        EXPECT_NEAR(volume * rho, p.mass, 1e-9 * p.mass) << body::getSegmentName(seg);
    }
    // Limbs: the truncated cone between the joint centres holds the mass and has its centroid
    // at the table's CoM (upper arm: uniform radius, see docs).
    for (Segment seg : {Segment::ThighR, Segment::ShankL, Segment::ForearmR}) {
        const body::SegmentParameters& p = a.get(seg);
        const double r1 = p.shape.radiusA, r2 = p.shape.radiusB, L = p.length;
        const double rho = body::getSegmentDensity(body::getSegmentType(seg));
        const double m = rho * SimTK::Pi * L * (r1 * r1 + r1 * r2 + r2 * r2) / 3;
        const double c =
            L * (r1 * r1 + 2 * r1 * r2 + 3 * r2 * r2) / (4 * (r1 * r1 + r1 * r2 + r2 * r2));
        EXPECT_NEAR(m, p.mass, 1e-9 * p.mass) << body::getSegmentName(seg);
        EXPECT_NEAR(c, -p.p_BC[1], 1e-9) << body::getSegmentName(seg);
    }
}

TEST(Anthropometry, MirrorSegmentsAreMirrored) {
    const body::Anthropometry a = body::calcAnthropometry(Sex::Female, 1.62, 58.0);
    for (int i = 0; i < body::kSegmentCount; ++i) {
        const Segment s = static_cast<Segment>(i);
        const Segment m = body::getMirrorSegment(s);
        EXPECT_EQ(body::getMirrorSegment(m), s);
        EXPECT_EQ(body::getSegmentType(m), body::getSegmentType(s));
        EXPECT_NEAR(a.get(m).p_WO[2], -a.get(s).p_WO[2], 1e-15);
        EXPECT_EQ(a.get(m).mass, a.get(s).mass);
    }
}
